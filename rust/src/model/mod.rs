//! The physics assembled from a configuration: beam bases and layers, their couplings, the
//! structure's matrices, the FE–SEA correction of the rail, dampers, the wheel–rail contact,
//! the vehicle models and the band a discretisation resolves; [`Model`] holds one run's.

pub mod basis;
pub mod contact;
pub mod couplings;
pub mod dampers;
pub mod fesea;
pub mod layers;
pub mod resolution;
pub mod structure;
pub mod substructures;
pub mod vehicle;

use crate::config::{Config, Profile};
use crate::error::Result;
use crate::model::structure::Structure;
use crate::model::vehicle::Vehicle;

#[derive(Clone, Debug)]
pub struct Model {
    pub cfg: Config,
    pub profile: Profile,
    pub structure: Structure,
    pub cars: Vec<Vehicle>,
}

impl Model {
    /// Assembles the structure of a configuration validated against `profile`
    /// (`crate::check::validated`).
    pub fn build(cfg: Config, profile: Profile) -> Result<Self> {
        let structure = Structure::build(&cfg)?;
        Ok(Self::with_structure(cfg, profile, structure))
    }

    /// The model of `cfg` on a structure assembled already (from a configuration of the
    /// same `Structure::key`).
    pub fn with_structure(cfg: Config, profile: Profile, structure: Structure) -> Self {
        let cars = cfg.vehicles.iter().map(Vehicle::new).collect();
        Self {
            cfg,
            profile,
            structure,
            cars,
        }
    }
}
