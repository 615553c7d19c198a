//! The structure against itself: layer names, meshes and extents, couplings on the layers
//! they join, and the discretisation against the structure.

use super::*;

/// Layers (names, meshes, extents, bases) and couplings (layers, positions, ranges);
/// returns the structure's length.
pub(super) fn layers_and_couplings(cfg: &Config) -> Result<f64> {
    let s = &cfg.structure;
    let length = positive("structure.length", s.length)?;
    if s.layers.is_empty() {
        return Err(VtbError::config(
            "structure.layers",
            "[]",
            "at least one layer is required",
        ));
    }
    for (i, l) in s.layers.iter().enumerate() {
        let p = format!("structure.layers[{i}]");
        l.validate(&p)?;
        if s.layers[..i].iter().any(|o| o.name == l.name) {
            return Err(VtbError::config(
                format!("{p}.name"),
                format!("{:?}", l.name),
                "layer names must be unique",
            ));
        }
        layer_mesh(cfg, l, &p, length)?;
        extent(cfg, l, &p, length)?;
        if cfg.discretisation.method != Method::Fem {
            if l.modes == 0 {
                return Err(VtbError::config(
                    format!("{p}.modes"),
                    0,
                    "at least one sine mode is required",
                ));
            }
            if l.modes + l.local_modes > MAX_MODES {
                return Err(VtbError::config(
                    format!("{p}.modes"),
                    l.modes + l.local_modes,
                    format!("modes + local_modes must be <= {MAX_MODES}"),
                ));
            }
        }
    }
    for (i, c) in s.couplings.iter().enumerate() {
        let p = format!("structure.couplings[{i}]");
        let (upper, _) = layer_pair(
            cfg,
            &p,
            &c.upper,
            &c.lower,
            "a layer cannot be coupled to itself",
        )?;
        c.validate(&p)?;
        match c.kind {
            CouplingKind::Discrete => {
                for (j, &x) in c.positions.iter().enumerate() {
                    let field = format!("{p}.positions[{j}]");
                    on_layer(cfg, &field, x, upper)?;
                    if let Some(lower) = cfg.layer_index(&c.lower) {
                        on_layer(cfg, &field, x, lower)?;
                    }
                }
            }
            CouplingKind::Continuous => coupling_range(cfg, c, &p, upper)?,
        }
    }
    Ok(length)
}

/// The discretisation against the structure.
pub(super) fn discretisation(cfg: &Config) -> Result<()> {
    let s = &cfg.structure;
    let d = &cfg.discretisation;
    for (field, cutoff, what) in [
        (
            "synthesis_cutoff",
            d.synthesis_cutoff,
            "the synthesis reduces",
        ),
        (
            "substructure_cutoff",
            d.substructure_cutoff,
            "substructures reduce",
        ),
    ] {
        let Some(fc) = cutoff else { continue };
        let field = format!("discretisation.{field}");
        let fc = positive(&field, fc)?;
        if d.method != Method::Fem {
            return Err(VtbError::config(
                field,
                fc,
                format!(
                    "{what} a finite-element structure (discretisation.method = \"fem\", not {:?})",
                    d.method
                ),
            ));
        }
    }
    if let (Some(_), Some(fc)) = (d.synthesis_cutoff, d.substructure_cutoff) {
        return Err(VtbError::config(
            "discretisation.substructure_cutoff",
            fc,
            "a structure runs on one engine: clear discretisation.synthesis_cutoff or this",
        ));
    }
    if d.method == Method::Fem && !(2..=MAX_ELEMENTS).contains(&d.fem_elements) {
        return Err(VtbError::config(
            "discretisation.fem_elements",
            d.fem_elements,
            format!("must be within [2, {MAX_ELEMENTS}]"),
        ));
    }
    if let Some([lo, hi]) = d.excitation_wavelengths {
        positive("discretisation.excitation_wavelengths[0]", lo)?;
        positive("discretisation.excitation_wavelengths[1]", hi)?;
        if hi < lo {
            return Err(VtbError::config(
                "discretisation.excitation_wavelengths[1]",
                hi,
                format!("must not be shorter than excitation_wavelengths[0] = {lo}"),
            ));
        }
    }
    if let Some(w) = d.omega_r {
        positive("discretisation.omega_r", w)?;
    }
    if d.method == Method::Hybrid && s.layers[0].local_modes == 0 {
        return Err(VtbError::config(
            "structure.layers[0].local_modes",
            0,
            "the hybrid method needs local modes on the top layer",
        ));
    }
    Ok(())
}

/// A layer's start and end: within the structure, in order, finite elements only.
fn extent(cfg: &Config, l: &LayerConfig, p: &str, length: f64) -> Result<()> {
    let start = within(
        &format!("{p}.start"),
        l.start.unwrap_or(0.0),
        0.0,
        length,
        "the structure",
    )?;
    let end = within(
        &format!("{p}.end"),
        l.end.unwrap_or(length),
        0.0,
        length,
        "the structure",
    )?;
    if end <= start {
        return Err(VtbError::config(
            format!("{p}.end"),
            end,
            format!("must be greater than the layer's start {start}"),
        ));
    }
    let mut last = start;
    for (j, &x) in l.joints.iter().enumerate() {
        let field = format!("{p}.joints[{j}]");
        within(&field, x, start, end, "the layer")?;
        if x <= last || x >= end {
            return Err(VtbError::config(
                field,
                x,
                "joints must lie inside the layer, in increasing order",
            ));
        }
        last = x;
        if cfg.discretisation.method != Method::Fem {
            return Err(VtbError::config(
                field,
                x,
                "a joint needs finite elements (discretisation.method = \"fem\")",
            ));
        }
    }
    if (start > 0.0 || end < length) && cfg.discretisation.method != Method::Fem {
        let field = if start > 0.0 { "start" } else { "end" };
        return Err(VtbError::config(
            format!("{p}.{field}"),
            if start > 0.0 { start } else { end },
            format!(
                "a layer over part of the structure needs finite elements                      (discretisation.method = \"fem\", not {:?}): a modal basis spans the whole length",
                cfg.discretisation.method
            ),
        ));
    }
    Ok(())
}

/// A continuous coupling's range: within the layers it joins, in order; finite elements
/// for a range other than the default.
fn coupling_range(cfg: &Config, c: &CouplingConfig, p: &str, upper: usize) -> Result<()> {
    let (a0, a1) = cfg.extent(upper);
    let (b0, b1) = cfg
        .layer_index(&c.lower)
        .map_or((a0, a1), |l| cfg.extent(l));
    let (lo, hi) = (a0.max(b0), a1.min(b1));
    if hi <= lo {
        return Err(VtbError::config(
            format!("{p}.lower"),
            format!("{:?}", c.lower),
            format!("layers {:?} and {:?} do not overlap", c.upper, c.lower),
        ));
    }
    let what = "the part of the structure both layers cover";
    let start = within(&format!("{p}.start"), c.start.unwrap_or(lo), lo, hi, what)?;
    let end = within(&format!("{p}.end"), c.end.unwrap_or(hi), lo, hi, what)?;
    if end <= start {
        return Err(VtbError::config(
            format!("{p}.end"),
            end,
            format!("must be greater than the coupling's start {start}"),
        ));
    }
    if (c.start.is_some() || c.end.is_some()) && cfg.discretisation.method != Method::Fem {
        return Err(VtbError::config(
            format!("{p}.{}", if c.start.is_some() { "start" } else { "end" }),
            c.start.or(c.end).expect("one is set"),
            "a continuous coupling over part of the structure needs finite elements \
             (discretisation.method = \"fem\")",
        ));
    }
    Ok(())
}

/// Timoshenko properties (both or neither, finite elements only) and the element length.
fn layer_mesh(cfg: &Config, l: &LayerConfig, p: &str, length: f64) -> Result<()> {
    let fem = cfg.discretisation.method == Method::Fem;
    match (l.shear_modulus, l.shear_coefficient) {
        (None, None) => {}
        (Some(g), Some(k)) => {
            positive(&format!("{p}.shear_modulus"), g)?;
            positive(&format!("{p}.shear_coefficient"), k)?;
            if !fem {
                return Err(VtbError::config(
                    format!("{p}.shear_modulus"),
                    format!("{g:?}"),
                    "Timoshenko layers need discretisation.method = \"fem\" (the modal \
                     basis is Euler–Bernoulli)",
                ));
            }
        }
        (g, _) => {
            let (field, other) = if g.is_none() {
                ("shear_modulus", "shear_coefficient")
            } else {
                ("shear_coefficient", "shear_modulus")
            };
            return Err(VtbError::config(
                format!("{p}.{field}"),
                "None",
                format!(
                    "a Timoshenko layer needs both shear_modulus and shear_coefficient ({other} is set)"
                ),
            ));
        }
    }
    if let Some(h) = l.element_length {
        let h = positive(&format!("{p}.element_length"), h)?;
        if length / h > MAX_ELEMENTS as f64 {
            return Err(VtbError::config(
                format!("{p}.element_length"),
                format!("{h:?}"),
                format!("gives more than {MAX_ELEMENTS} elements"),
            ));
        }
    }
    Ok(())
}
