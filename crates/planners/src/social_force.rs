//! Social force (placeholder while written).
use crate::{Command, Observation, ParamError, ParamReader, Params, Planner};
/// DWA.
pub struct SocialForce;
impl SocialForce {
    /// From params.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        ParamReader::new("social-force", params).finish()?;
        Ok(SocialForce)
    }
}
impl Planner for SocialForce {
    fn plan(&mut self, obs: &Observation) -> Command {
        Command::Velocity(obs.me.velocity)
    }
}
