//! Shared by the benches: the irregularity sample of vtb.paper_config() (benches/data,
//! written by benches/make_fixture.py), so that the benches run without Python.

use std::path::Path;
use vtb::Profile;

pub fn paper_profile() -> Profile {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data");
    let meta: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("paper_profile.json")).expect("fixture json"),
    )
    .expect("json");
    let bytes = std::fs::read(dir.join("paper_profile.f64")).expect("fixture data");
    let values = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    Profile {
        x0: meta["x0"].as_f64().unwrap(),
        dx: meta["dx"].as_f64().unwrap(),
        values,
        treads: Vec::new(),
    }
}

/// The machine's load (the 1, 5 and 15 min averages of /proc/loadavg; "unknown" elsewhere),
/// printed with every timing: the machine is shared, so a time means little without it.
pub fn machine_load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| {
            let v: Vec<&str> = s.split_whitespace().take(3).collect();
            (v.len() == 3)
                .then(|| format!("load average {} {} {} (1, 5, 15 min)", v[0], v[1], v[2]))
        })
        .unwrap_or_else(|| "load unknown".into())
}
