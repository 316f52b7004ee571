//! `taskstack fk`: forward kinematics as JSON lines.

use std::collections::HashMap;
use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, ValueEnum};
use serde_json::{Map, Value, json};
use taskstack::human::Side;
use taskstack::model::{Model, UrdfOptions};

use crate::options::robot_profile;

/// Forward kinematics of a robot, as JSON lines on stdin and stdout.
///
/// Reads one JSON object per line, {"q": {"LShoulderPitch": 0.5, ...}} (joint names of the
/// model, radians; missing joints are 0; blank lines are skipped), and writes one line per
/// input, {"frames": {"l_hand": [x, y, z], ...every named frame...}, "com": [x, y, z]}: metres in
/// the root frame (x forward, y left, z up). A coupled joint (the NAO's RHipYawPitch, driven by
/// LHipYawPitch) may be given by either name; two names of one motor with different values are
/// an error. Errors name the input line and stop the command (exit status 1).
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct FkArgs {
    /// The robot: nao, g1 or a biped profile file (TOML).
    #[arg(long, value_name = "nao|g1|PROFILE.toml", default_value = "nao")]
    robot: String,
    /// The sole the model is rooted at (its frame is the output frame).
    #[arg(long, value_enum, default_value_t = Root::Right)]
    root: Root,
    /// Instead of --robot: any URDF, rooted at its own root link, with its links as frames.
    #[arg(long, value_name = "FILE.urdf", conflicts_with_all = ["robot", "root"])]
    urdf: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Root {
    /// The right sole.
    #[value(alias = "r_sole")]
    Right,
    /// The left sole.
    #[value(alias = "l_sole")]
    Left,
}

pub(crate) fn run(args: FkArgs) -> Result<ExitCode> {
    let model = match &args.urdf {
        Some(path) => Model::from_urdf_file(path, &UrdfOptions::default())
            .with_context(|| format!("--urdf {}", path.display()))?,
        None => {
            let side = match args.root {
                Root::Right => Side::Right,
                Root::Left => Side::Left,
            };
            robot_profile(&args.robot)?.model(side).clone()
        }
    };
    let mut data = model.new_data();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for (number, line) in std::io::stdin().lock().lines().enumerate() {
        let line = line.context("cannot read stdin")?;
        if line.trim().is_empty() {
            continue;
        }
        let q = parse_q(&model, &line).with_context(|| format!("input line {}", number + 1))?;
        model.forward_kinematics(&mut data, &q)?;
        let mut frames = Map::new();
        for (frame, placement) in model.frames().iter().zip(data.frame_placements()) {
            let p = placement.translation.vector;
            frames.insert(frame.name.clone(), json!([p.x, p.y, p.z]));
        }
        let com = model.com(&data)?;
        writeln!(
            out,
            "{}",
            json!({ "frames": frames, "com": [com.x, com.y, com.z] })
        )?;
        out.flush()?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `q` in the model's variable order from a `{"q": {...}}` line. A joint name maps to its
/// variable through the joint's coupling (angle = multiplier · q + offset).
fn parse_q(model: &Model, line: &str) -> Result<Vec<f64>> {
    let value: Value = serde_json::from_str(line).context("malformed JSON")?;
    let joints = value
        .get("q")
        .and_then(Value::as_object)
        .ok_or_else(|| anyhow!("expected an object {{\"q\": {{joint: value, ...}}}}"))?;
    let mut q = vec![0.0; model.nv()];
    let mut given: HashMap<usize, (&str, f64)> = HashMap::new();
    for (name, v) in joints {
        let angle = v
            .as_f64()
            .ok_or_else(|| anyhow!("joint `{name}`: not a number"))?;
        let (variable, value) = match model.variable_index(name) {
            Ok(k) => (k, angle),
            Err(_) => {
                let joint = (model.joints().iter())
                    .find(|j| j.name == *name && j.variable.is_some())
                    .ok_or_else(|| anyhow!("unknown joint `{name}`"))?;
                let k = joint.variable.unwrap_or_default();
                (k, (angle - joint.offset) / joint.multiplier)
            }
        };
        if let Some((other, before)) = given.insert(variable, (name, value))
            && before != value
        {
            bail!("{other} ({before}) and {name} ({angle}) differ: they are one motor");
        }
        q[variable] = value;
    }
    Ok(q)
}
