//! Observation points on their layers, the analysis window, band limits, band levels and
//! the names of the requested indices.

use super::*;

/// Observation points on their layers, the metrics' window, bands and index names.
pub(super) fn points_and_indices(cfg: &Config, dt: f64) -> Result<()> {
    for (i, &x) in cfg.output.points.iter().enumerate() {
        for li in crate::outputs::index_layers(cfg) {
            on_layer(cfg, &format!("output.points[{i}]"), x, li)?;
        }
    }
    if let Some([t0, t1]) = cfg.output.window {
        non_negative("output.window[0]", t0)?;
        finite("output.window[1]", t1)?;
        let end = cfg.n_steps() as f64 * dt;
        if !(t1 > t0) || t0 >= end {
            return Err(VtbError::config(
                "output.window",
                format!("[{t0:?}, {t1:?}]"),
                format!("must be an interval t0 < t1 that starts within the run [0, {end:?}] s"),
            ));
        }
    }
    if let Some(fc) = cfg.output.band_limit {
        crate::outputs::filter::check("output.band_limit", fc, dt)?;
    }
    crate::outputs::filter::check("output.deck_band", cfg.output.deck_band, dt)?;
    let steps = crate::outputs::window_steps(cfg.output.window, dt, cfg.n_steps());
    for (i, &f) in cfg.output.band_levels.iter().enumerate() {
        let n = steps.clone().count();
        crate::outputs::bands::check(&format!("output.band_levels[{i}]"), f, dt, n)?;
    }
    if let Some(names) = &cfg.output.indices {
        let known = crate::outputs::index_names(cfg);
        for (i, n) in names.iter().enumerate() {
            if !known.contains(n) {
                return Err(VtbError::config(
                    format!("output.indices[{i}]"),
                    n,
                    format!(
                        "is not an index of this configuration; it has {}",
                        known.join(", ")
                    ),
                ));
            }
        }
    }
    Ok(())
}
