//! Priority preservation on the real imitation stacks: for every phase's task table on the NAO
//! (the executable tables the imitator uses and the contact-first variant of Table I),
//! at random configurations within the limits and random task velocities, the residual of each
//! level is the same (to 1e-9 relative) whether or not the levels below it and the gradient tasks
//! are present. Jacobians come from the DH NAO rooted at the table's sole. The executable tables'
//! self-collision level is kept with its bounds open (±∞, never active): the bounds' own tests
//! are `solver_inequalities`.

use nalgebra::Vector3;
use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::imitation::phase::tables::{Task, TaskTable, TaskTables};
use taskstack::imitation::phase::{PhaseConfig, SupportPhase};
use taskstack::model::{Axis, Model};
use taskstack::robots::nao;
use taskstack::solver::{Solver, StackShape};

fn model(foot: Side) -> Model {
    match foot {
        Side::Right => nao::rfoot(),
        Side::Left => nao::lfoot(),
    }
}

fn borrowed(named: &[(String, usize)]) -> Vec<(&str, usize)> {
    named.iter().map(|(n, r)| (n.as_str(), *r)).collect()
}

/// A solver for the first `levels` levels of `table`, filled at `q` with desired velocities
/// from `targets` (one per row, in stack order) and, if given, a gradient term.
fn filled(
    table: &TaskTable,
    model: &Model,
    q: &[f64],
    levels: usize,
    targets: &[f64],
    gradient: Option<&[f64]>,
) -> Solver {
    let full = table.shape(model.nv());
    let shape = full.levels()[..levels]
        .iter()
        .fold(StackShape::new(model.nv()), |s, l| {
            let named = |specs: &[taskstack::solver::TaskSpec]| -> Vec<(String, usize)> {
                specs.iter().map(|t| (t.name.clone(), t.rows)).collect()
            };
            let (tasks, inequalities) = (named(&l.tasks), named(&l.inequalities));
            s.with_mixed_level(&l.name, &borrowed(&tasks), &borrowed(&inequalities))
        });
    let mut solver = Solver::new(&shape).unwrap();
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let mut k = 0;
    for (j, level) in table.levels[..levels].iter().enumerate() {
        let mut l = solver.stack_mut().level_mut(j);
        let mut row = 0;
        for task in &level.tasks {
            let rows = task.rows();
            let mut jac = l.jacobian_mut().subrows_mut(row, rows);
            match task {
                Task::ComXY(_) => model.com_jacobian_rows(&data, 2, jac).unwrap(),
                Task::ComHeight => model.com_jacobian_axes(&data, &[Axis::Z], jac).unwrap(),
                Task::Point {
                    frame,
                    offset,
                    axes,
                    ..
                } => {
                    let id = model.frame_id(frame).unwrap();
                    let picked = [(axes.x, Axis::X), (axes.y, Axis::Y), (axes.z, Axis::Z)];
                    for (r, (_, axis)) in picked.iter().filter(|(on, _)| *on).enumerate() {
                        model
                            .point_jacobian_row(
                                &data,
                                id,
                                &Vector3::from(*offset),
                                *axis,
                                jac.as_mut().subrows_mut(r, 1),
                            )
                            .unwrap();
                    }
                }
                Task::Orientation { frame, .. } => {
                    // Held-flat tasks use all three angular-velocity rows, upright ones the
                    // first two.
                    let id = model.frame_id(frame).unwrap();
                    let mut all = faer::Mat::zeros(3, model.nv());
                    model.orientation_jacobian(&data, id, all.as_mut()).unwrap();
                    jac.copy_from(all.as_ref().subrows(0, rows));
                }
            }
            row += rows;
        }
        let n = l.rows();
        l.target_mut().copy_from_slice(&targets[k..k + n]);
        k += n;
    }
    if let Some(g) = gradient {
        solver.stack_mut().gradient_mut().copy_from_slice(g);
    }
    solver
}

fn residuals(mut solver: Solver) -> Vec<f64> {
    solver
        .solve_unbounded()
        .unwrap()
        .report
        .levels()
        .iter()
        .map(|l| l.residual)
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn levels_are_not_disturbed_by_lower_levels_or_gradients(
        phase in 0usize..SupportPhase::COUNT,
        executable in any::<bool>(),
        unit in prop::collection::vec(0.0f64..1.0, 23),
        targets in prop::collection::vec(-0.2f64..0.2, 20),
        gradient in prop::collection::vec(-1.0f64..1.0, 23),
    ) {
        let config = PhaseConfig::default();
        let tables = if executable {
            TaskTables::executable(&config, &nao::profile())
        } else {
            TaskTables::contact_first(&config, &nao::profile())
        };
        let table = tables.table(SupportPhase::ALL[phase]);
        let model = model(table.model_root);
        let q: Vec<f64> = model.variables().iter().zip(&unit).map(|(v, u)| v.lower + u * (v.upper - v.lower)).collect();
        let total: usize = table.levels.iter().flat_map(|l| &l.tasks).map(Task::rows).sum();
        let targets = &targets[..total];
        let full = residuals(filled(table, &model, &q, table.levels.len(), targets, Some(&gradient)));
        for j in 0..table.levels.len() {
            let alone = residuals(filled(table, &model, &q, j + 1, targets, None));
            let scale = full[j].abs().max(alone[j].abs()).max(1.0);
            prop_assert!((full[j] - alone[j]).abs() <= 1e-9 * scale,
                "{}: level {j} residual {} with the levels below and the gradients, {} without", table.phase, full[j], alone[j]);
        }
    }
}
