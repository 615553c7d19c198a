//! The judge of a configuration: every validation phase, the plausible ranges and the memory
//! budget, above the model and the outputs it consults.

pub mod budget;
pub mod plausibility;
