//! Dynamic window approach (placeholder while written).
use crate::{Command, Observation, ParamError, ParamReader, Params, Planner};
/// DWA.
pub struct Dwa;
impl Dwa {
    /// From params.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        ParamReader::new("dwa", params).finish()?;
        Ok(Dwa)
    }
}
impl Planner for Dwa {
    fn plan(&mut self, obs: &Observation) -> Command {
        Command::Velocity(obs.me.velocity)
    }
}
