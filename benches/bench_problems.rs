//! The whole `solve` frame on the NAO benchmark problems (`tests/data/bench/problem_*.json`):
//! targets set + all driver iterations + stop test, warm-started from the previous frame, cycling
//! through the file's frames. Same code as the `solve` example (`taskstack::problem`). Each
//! problem three times: by the strict hierarchy (as the files ask), by weighted damped least
//! squares (λ = 1e-3, `solve_frame_dls/…`), to compare the two solver methods, and with the CoM
//! task replaced by an inequality level: its ground projection inside the support polygon shrunk
//! by 1 cm (`solve_frame_com_polygon/…`), solved by the active-set method.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use taskstack::problem::{Problem, Runner};
use taskstack::solver::Method;

fn bench(c: &mut Criterion) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bench");
    for name in [
        "problem_rs",
        "problem_ds",
        "problem_rs_stress",
        "problem_ds_stress",
    ] {
        let path = dir.join(format!("{name}.json"));
        let Ok(text) = std::fs::read_to_string(&path) else {
            eprintln!("skipping {}: not found", path.display());
            continue;
        };
        let strict = Problem::from_json(&text).expect("valid problem file");
        let mut dls = strict.clone();
        dls.method = Method::WeightedDls { damping: 1e-3 };
        let mut polygon = strict.clone();
        polygon.com_polygon_margin = Some(0.01);
        for (label, problem) in [
            ("solve_frame", strict),
            ("solve_frame_dls", dls),
            ("solve_frame_com_polygon", polygon),
        ] {
            bench_problem(c, &format!("{label}/{name}"), &problem);
        }
    }
}

/// Frames of `problem` in a loop, from its initial posture again after the last.
fn bench_problem(c: &mut Criterion, id: &str, problem: &Problem) {
    let mut runner = Runner::new(problem).expect("solver for the problem");
    let mut q = problem.q_init.clone();
    let mut frame = 0;
    c.bench_function(id, |b| {
        b.iter(|| {
            if frame == problem.frames {
                frame = 0;
                q.copy_from_slice(&problem.q_init);
            }
            let result = runner.solve_frame(frame, &mut q).expect("frame solves");
            frame += 1;
            black_box(result.iterations)
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
