//! Lockstep throughput (`cargo bench --bench lockstep [-- --converged]`): a group of 16 TID
//! jobs of the article's case (the hybrid with 10 rail–slab TIDs, the cases of a sweep:
//! one model, 16 damper parameter sets) run by `run_batch` on one thread with lockstep groups
//! of 1 (every job alone), 2, 4 and 8 lanes, and the throughput of each against the jobs run
//! one after another with `simulate`. Every width is checked to give each job's metrics bit
//! for bit. Rounds alternate the variants and the best of each is kept (the machine is shared).
//! `--converged` runs 4 jobs of the converged preset instead (finite elements, block engine).

mod common;

use std::time::Instant;
use vtb::config::{Config, DamperGroup};
use vtb::library::presets;
use vtb::{BatchOptions, Job, Record, run_batch, simulate};

fn tid_jobs(base: &Config, n: usize, profile: &std::sync::Arc<vtb::Profile>) -> Vec<Job> {
    // The article's grid (b_t, k_t, c_t), strided so that the 16 cases spread over it.
    let cases = (0..n).map(|i| {
        let b = (1 + i % 10) as f64;
        let k = [1e4, 5e5, 2e7, 1e8, 3e8, 7e8, 1e9][i % 7];
        let c = [10.0, 100.0, 1e3, 1e4][i % 4];
        (b, k, c)
    });
    cases
        .map(|(b, k, c)| {
            let mut cfg = base.clone();
            cfg.dampers = vec![DamperGroup {
                name: Some("tids".into()),
                inertance: b,
                stiffness: k,
                damping: c,
                kind: vtb::config::DamperKind::Tid,
                count: Some(10),
                x0: Some(77.12),
                spacing: Some(0.64),
                positions: None,
                upper: "rail".into(),
                lower: "slab".into(),
            }];
            Job {
                config: cfg,
                profile: profile.clone(),
            }
        })
        .collect()
}

fn main() {
    let converged = std::env::args().any(|a| a == "--converged");
    let (base, n, rounds) = if converged {
        (presets::paper_converged(), 4, 1)
    } else {
        (presets::paper(), 16, 3)
    };
    let profile = std::sync::Arc::new(common::paper_profile());
    let jobs = tid_jobs(&base, n, &profile);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let widths: &[usize] = if converged { &[1, 4] } else { &[1, 2, 4, 8] };
    let mut single = f64::INFINITY;
    let mut best = vec![f64::INFINITY; widths.len()];
    let reference: Vec<_> = jobs
        .iter()
        .map(|j| simulate(&j.config, &j.profile, None).unwrap().metrics())
        .collect();
    for _ in 0..rounds {
        let t = Instant::now();
        for j in &jobs {
            simulate(&j.config, &j.profile, None).unwrap();
        }
        single = single.min(t.elapsed().as_secs_f64());
        for (wi, &w) in widths.iter().enumerate() {
            let opts = BatchOptions {
                record: Record::Metrics,
                max_lanes: w,
            };
            let t = Instant::now();
            let out = pool.install(|| run_batch(&jobs, opts, None, None));
            best[wi] = best[wi].min(t.elapsed().as_secs_f64());
            for (r, m) in out.iter().zip(&reference) {
                let got = r.as_ref().expect("job runs").metrics();
                for (k, v) in m {
                    assert_eq!(v.to_bits(), got[k].to_bits(), "width {w}: {k} differs");
                }
            }
        }
    }
    println!(
        "{} jobs ({}), one thread: {n} single runs {single:.2} s ({:.3} s per job)",
        n,
        if converged {
            "converged preset"
        } else {
            "article hybrid, 10 TIDs"
        },
        single / n as f64
    );
    for (w, t) in widths.iter().zip(&best) {
        println!(
            "  lockstep groups of {w}: {t:.2} s ({:.3} s per job), throughput x{:.2} of single runs; metrics bit-identical",
            t / n as f64,
            single / t
        );
    }
    println!("  {}", common::machine_load());
}
