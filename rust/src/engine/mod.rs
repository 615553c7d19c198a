//! The engines: what runs a validated model in time.
//!
//! - `batch`: the entrance — one run or many jobs, grouped by model into lockstep lanes and
//!   dispatched to the engine a configuration asks for;
//! - `coupled`: what every engine shares — the vehicles, their contact with the rail, the
//!   moving forces, the records, the residual filter of truncated modes under a wheel;
//! - `integrator`: the Newmark stepper of a linear subsystem with contact ports (the cars' and
//!   the finite-element / modal structure's);
//! - `newmark`: the structure stepped by Newmark (modal, hybrid FE–SEA or finite elements);
//! - `synthesis`: the structure as complex modes stepped exactly (docs/synthesis.md).

mod batch;
pub(crate) mod coupled;
pub mod integrator;
pub mod newmark;
pub mod synthesis;

pub use batch::{
    BatchOptions, Reduced, Sink, model_key, run_batch, run_batch_each, run_batch_with, simulate,
    simulate_with,
};
pub use coupled::residual::{Filter, FilterStep};

use crate::config::DamperParams;
use crate::config::{Config, Profile};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// What the caller of a run sees and steers while it runs, from another thread: the cancel
/// flag, polled every [`CANCEL_POLL`] steps, and at each poll the steps done of the run's total
/// (for a progress bar).
#[derive(Debug, Default)]
pub struct Control {
    cancel: AtomicBool,
    done: AtomicUsize,
    total: AtomicUsize,
}

impl Control {
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the run to stop at its next poll (it ends with [`VtbError::Cancelled`]).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// (steps done, steps in all) at the last poll; (0, 0) before the first.
    pub fn progress(&self) -> (usize, usize) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

/// A run's poll at `step` of `total`: notes its progress and says whether to stop.
pub(crate) fn poll(control: Option<&Control>, step: usize, total: usize) -> bool {
    control.is_some_and(|c| {
        c.done.store(step, Ordering::Relaxed);
        c.total.store(total, Ordering::Relaxed);
        c.cancelled()
    })
}

/// Steps between polls of the cancel flag (well under a second on every model).
pub(crate) const CANCEL_POLL: usize = 64;

/// Steps between checks that every state is finite.
pub(crate) const FINITE_POLL: usize = 1024;

pub use crate::config::fields::MAX_LANES;

/// The default widest group, chosen by measurement (`cargo bench --bench lockstep`, docs).
pub const DEFAULT_LANES: usize = 4;

/// The default widest group on a reduction: its lanes share the wheels' modal shapes, a
/// pass over a few rows of ψ per wheel and step (measured, docs/synthesis.md: 8 lanes on 2
/// cores run a TID sweep's cases 1.35× faster than 4).
pub const SYNTHESIS_LANES: usize = 8;

/// One job of a batch: a configuration and its (possibly shared) irregularity profile.
#[derive(Clone, Debug)]
pub struct Job {
    pub config: Config,
    pub profile: Arc<Profile>,
}

/// What a lane of a lockstep group owns: its irregularity and its dampers' parameters.
#[derive(Clone, Debug)]
pub struct LaneSpec<'a> {
    pub profile: &'a Profile,
    /// One per damper of the model (empty without dampers).
    pub dampers: Vec<DamperParams>,
}

impl<'a> LaneSpec<'a> {
    pub fn of(config: &Config, profile: &'a Profile) -> Self {
        Self {
            profile,
            dampers: config.damper_params(),
        }
    }
}
