//! A validated, assembled model: configuration, irregularity, structure matrices and cars.

use crate::config::{Config, Profile};
use crate::error::Result;
use crate::structure::Structure;
use crate::vehicle::Vehicle;

#[derive(Clone, Debug)]
pub struct Model {
    pub cfg: Config,
    pub profile: Profile,
    pub structure: Structure,
    pub cars: Vec<Vehicle>,
}

impl Model {
    /// Validates `cfg` against `profile` and assembles the structure.
    pub fn new(cfg: Config, profile: Profile) -> Result<Self> {
        cfg.validate(&profile)?;
        Self::build(cfg, profile)
    }

    /// Assembles the structure of a configuration already validated against `profile`.
    pub fn build(cfg: Config, profile: Profile) -> Result<Self> {
        let structure = Structure::build(&cfg)?;
        let cars = cfg.vehicles.iter().map(Vehicle::new).collect();
        Ok(Self {
            cfg,
            profile,
            structure,
            cars,
        })
    }
}
