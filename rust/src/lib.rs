//! vtb — vehicle–track–bridge vertical dynamics.
//!
//! The core library: beam layers in a modal (Hermite + sine) or finite-element basis,
//! couplings, vehicle models (Zhai's 10-DOF car, a quarter car), Hertz contact, dampers,
//! Newmark integration and the complex-modal synthesis of a finite-element structure. It has
//! no Python types; the `vtb._core` extension module in `rust/bindings` wraps it.
//!
//! ```no_run
//! use vtb::{Config, Profile, simulate};
//! let cfg = Config::from_json(&std::fs::read_to_string("config.json").unwrap()).unwrap();
//! let result = simulate(&cfg, &Profile::flat(), None).unwrap();
//! println!("{:?}", result.metrics());
//! ```

// `!(x > 0.0)` also refuses NaN: the validation's idiom, kept over `partial_cmp`.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The numeric kernels walk several arrays with one index; iterator chains would hide that.
#![allow(clippy::needless_range_loop)]

pub mod bands;
pub mod basis;
pub mod budget;
pub mod comfort;
pub mod config;
pub mod contact;
pub mod couplings;
pub mod dampers;
pub mod error;
pub mod fesea;
pub mod filter;
pub mod indices;
pub mod integrator;
pub mod layers;
pub mod linalg;
pub mod model;
pub mod plausibility;
pub mod presets;
pub mod resolution;
pub mod results;
pub mod simulate;
pub mod structure;
pub mod synthesis;
pub mod trains;
pub mod vehicle;

pub use config::{Config, Profile};
pub use error::{Result, VtbError};
pub use model::Model;
pub use results::{Record, RunResult};
pub use simulate::{
    BatchOptions, Control, Job, Sink, run_batch, run_batch_each, run_batch_with, simulate,
    simulate_with,
};
