//! Table I rendered as markdown, row by row as the paper prints it ([`TaskTable`]'s and
//! [`TaskTables`]' `Display`).

use super::*;

/// Millimetres of a length in metres, for the rendering (`0.03` → `"30 mm"`, `0.0` → `"0"`).
fn mm(metres: f64) -> String {
    if metres == 0.0 {
        return "0".to_owned();
    }
    format!("{} mm", (metres * 1000.0 * 1000.0).round() / 1000.0)
}

fn point_mm([x, y]: [f64; 2]) -> String {
    format!("[{}, {}]", mm(x), mm(y))
}

struct ComCell<'a>(&'a ComGoal, Side);

impl fmt::Display for ComCell<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (root, free) = (foot_name(self.1), foot_name(self.1.other()));
        let other = format!("{free} ankle");
        match *self.0 {
            ComGoal::SupportAnkle => f.write_str("[0, 0]"),
            ComGoal::SupportFootCentre { lambda } => write!(f, "[λ, 0], λ = {}", mm(lambda)),
            ComGoal::MidAnkles => write!(f, "p({other}).xy / 2"),
            ComGoal::OtherFootCentre { lambda } => {
                write!(f, "p({other}).xy + λ·x̂({free} sole), λ = {}", mm(lambda))
            }
            ComGoal::SupportPoint(p) => write!(f, "{} in {root} sole", point_mm(p)),
            ComGoal::OtherPoint(p) => write!(f, "{} in {free} sole", point_mm(p)),
            ComGoal::BetweenPoints { support, other } => write!(
                f,
                "midway: {} in {root} sole, {} in {free} sole",
                point_mm(support),
                point_mm(other),
            ),
        }
    }
}

struct PointCell<'a>(&'a str, [f64; 3], Axes, PointTarget);

impl fmt::Display for PointCell<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let PointCell(frame, offset, axes, target) = *self;
        let point = if offset == [0.0; 3] {
            frame.to_owned()
        } else {
            let [x, y, z] = offset.map(mm);
            format!("{frame} + [{x}, {y}, {z}]")
        };
        let coords = if axes == Axes::XYZ {
            format!("p({point})")
        } else {
            format!("{}({point})", &axes.suffix()[1..])
        };
        match target {
            PointTarget::Scaled(joint) => write!(f, "{coords} ← {}", joint.name()),
            PointTarget::Held { lift } if axes == Axes::Z => write!(f, "{coords} = {}", mm(lift)),
            PointTarget::Held { lift: 0.0 } => write!(f, "{coords} held"),
            PointTarget::Held { lift } => write!(f, "{coords} held, lifted {}", mm(lift)),
            PointTarget::Standing { lower: 0.0 } => write!(f, "{coords} as standing"),
            PointTarget::Standing { lower } => write!(f, "{coords} as standing − {}", mm(lower)),
            PointTarget::Footstep { lift } => {
                write!(f, "{coords} over the footstep + {}", mm(lift))
            }
            PointTarget::HandContact(_) => write!(f, "{coords} on its contact, while a support"),
            PointTarget::Planned => write!(f, "{coords} as the walk plans"),
        }
    }
}

impl fmt::Display for TaskTable {
    /// One markdown row like Table I: Support | Step | Model | X_t | X'_c | Gradients (κ).
    /// Levels after the first CoM level are separated by ` ≻ ` (higher priority first).
    // One function on purpose (~90 lines): one pass over the levels filling the row's columns
    // left to right, as the paper's table reads.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut tracked = Vec::new();
        let mut coms = Vec::new();
        let mut rows = 0;
        for level in &self.levels {
            let mut cells = Vec::new();
            for task in &level.tasks {
                match task {
                    Task::ComXY(goal) => coms.push(ComCell(goal, self.model_root).to_string()),
                    Task::ComHeight => {
                        rows += task.rows();
                        cells.push("z(CoM) as the walk plans".to_owned());
                    }
                    Task::Point {
                        frame,
                        offset,
                        axes,
                        target,
                    } => {
                        rows += task.rows();
                        cells.push(PointCell(frame, *offset, *axes, *target).to_string());
                    }
                    Task::Orientation { frame, target } => {
                        rows += task.rows();
                        cells.push(match target {
                            OrientationTarget::HeldFlat => format!("R({frame}) flat, yaw held"),
                            OrientationTarget::Footstep => {
                                format!("R({frame}) flat, footstep yaw")
                            }
                            OrientationTarget::Upright { lean: 0.0 } => {
                                format!("z({frame}) vertical")
                            }
                            OrientationTarget::Upright { lean } => {
                                format!("z({frame}) leaning {lean:.2} rad about x")
                            }
                            OrientationTarget::Leaning => {
                                format!("z({frame}) leaning as the walk plans")
                            }
                            OrientationTarget::Facing { lean } => {
                                format!("R({frame}) leaning {lean:.2} rad, facing between the feet")
                            }
                        });
                    }
                }
            }
            for constraint in &level.constraints {
                cells.push(match constraint {
                    Constraint::Distance {
                        first,
                        second,
                        margin,
                    } => format!("d({first}, {second}) ≥ {}", mm(*margin)),
                    Constraint::Zmp {
                        margin,
                        max_yaw_moment,
                        ..
                    } => format!(
                        "ZMP in support ({} in), |τ_z| ≤ {max_yaw_moment:.2} N·m",
                        mm(*margin)
                    ),
                });
            }
            if !cells.is_empty() {
                tracked.push(cells.join(", "));
            }
        }
        let gradients: Vec<String> = self
            .gradients
            .iter()
            .map(|g| {
                let name = match g.kind {
                    GradientKind::JointLimits => "limits",
                    GradientKind::HumanJoints => "human joints",
                };
                format!("{name} {:.2}", g.kappa)
            })
            .collect();
        write!(
            f,
            "| {} | {} | {} | ({rows}×1) {} | ({}×1) {} | {}{} |",
            self.phase.support_name(),
            self.phase.step_name().unwrap_or(""),
            foot_name(self.model_root),
            tracked.join(" ≻ "),
            2 * coms.len(),
            coms.join("; "),
            gradients.join(", "),
            if self.clamping { "; clamping" } else { "" },
        )
    }
}

impl fmt::Display for TaskTables {
    /// The whole table as markdown (header, then one row per phase in Table I order).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "| Support | Step | Model | X_t | X'_c | Gradients (κ) |")?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for table in &self.tables {
            writeln!(f, "{table}")?;
        }
        Ok(())
    }
}
