//! Ready-made configurations: the article's presets and the train library.

pub mod presets;
pub mod trains;
