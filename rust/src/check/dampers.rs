//! Damper groups: their names, their dampers on their layers, and their total count.

use super::*;

/// Names a group may not take: the configuration's own fields, which a group's path would
/// shadow.
const RESERVED: [&str; 10] = [
    "structure",
    "discretisation",
    "vehicles",
    "forces",
    "speed",
    "solver",
    "output",
    "dampers",
    "accept_implausible",
    "irregularity",
];

/// Every damper group (`damper_groups`), and their total count.
pub(super) fn groups(cfg: &Config, length: f64) -> Result<()> {
    names(cfg)?;
    let mut total = 0;
    for (path, g) in cfg.damper_groups() {
        g.validate(&path, length)?;
        dampers_on_layers(cfg, &path, g)?;
        total += g.locations().len();
    }
    if total > MAX_TIDS {
        let (path, g) = cfg.damper_groups().pop().expect("dampers counted");
        return Err(VtbError::config(
            if g.positions.is_some() {
                format!("{path}.positions")
            } else {
                format!("{path}.count")
            },
            total,
            format!(
                "all groups together hold {total} dampers, more than {MAX_TIDS}: their \
                 coupling is a dense matrix inverted once per run and applied every step"
            ),
        ));
    }
    Ok(())
}

/// A group's layers exist, differ, and hold every one of its dampers.
fn dampers_on_layers(cfg: &Config, path: &str, g: &DamperGroup) -> Result<()> {
    let same = format!("must differ from {path}.upper");
    let (upper, lower) = layer_pair(cfg, path, &g.upper, &g.lower, &same)?;
    let field = match g.positions {
        Some(_) => format!("{path}.positions"),
        None => format!("{path}.x0"),
    };
    for i in std::iter::once(upper).chain(lower) {
        for x in g.locations() {
            on_layer(cfg, &field, x, i)?;
        }
    }
    Ok(())
}

/// A group's name is an identifier, not a field of the configuration, and unique.
fn names(cfg: &Config) -> Result<()> {
    for (i, g) in cfg.dampers.iter().enumerate() {
        let Some(name) = &g.name else { continue };
        let field = format!("dampers[{i}].name");
        let identifier = name
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !identifier || RESERVED.contains(&name.as_str()) {
            return Err(VtbError::config(
                field,
                format!("{name:?}"),
                "must be an identifier (letters, digits, _) other than a configuration field's \
                 name",
            ));
        }
        if cfg.dampers[..i]
            .iter()
            .any(|o| o.name.as_ref() == Some(name))
        {
            return Err(VtbError::config(
                field,
                format!("{name:?}"),
                "names another group too",
            ));
        }
    }
    Ok(())
}
