//! The routes of the robots with `route = "shortest"`, computed once for
//! the world when it is built: the same computation as each such robot's
//! agent makes, so routes.csv holds the route its planner was steered
//! along (a car's: its centre's along its route) and its `spl` is
//! measured against that route's length.

use mrsim_agents::route::RouteScene;
use mrsim_scenario::{Route as RouteKind, Scenario};
use mrsim_world::Route;
use std::collections::BTreeMap;

/// The route of every robot of `scenario` that asks for one, by name.
pub fn of(scenario: &Scenario) -> BTreeMap<String, Route> {
    let mut routes = BTreeMap::new();
    if !scenario
        .robots
        .iter()
        .any(|r| r.route == RouteKind::Shortest)
    {
        return routes;
    }
    let scene = RouteScene::of(scenario);
    for r in scenario
        .robots
        .iter()
        .filter(|r| r.route == RouteKind::Shortest)
    {
        // Validation refused every robot without a route.
        if let Ok((points, length)) = scene.line(r) {
            routes.insert(r.name.clone(), Route { points, length });
        }
    }
    routes
}
