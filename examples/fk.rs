//! Forward kinematics of the NAO as JSON lines.
//!
//! ```sh
//! cargo run --release --example fk -- --root r_sole|l_sole|torso|urdf:<path>
//! ```
//!
//! Reads one JSON object per line on stdin, `{"q": {"HeadYaw": 0.1, ...}}` (NAOqi joint names,
//! radians; missing joints are 0; blank lines are skipped), and writes one line per input,
//! `{"frames": {"l_hand": [x, y, z], ...every named frame...}, "com": [x, y, z]}`: positions in metres
//! in the root frame (x forward, y left, z up). Roots: `r_sole`, `l_sole`, `torso` are the built-in
//! DH models; `urdf:<path>` loads that URDF rooted at its own root link (the torso for the NAO) with
//! the same named frames. Without `--root`, `r_sole`.
//!
//! `RHipYawPitch` may be given: it is the same motor as `LHipYawPitch`, so if both are given and
//! differ the input is an error. Errors (malformed JSON, unknown joint name, non-numeric value,
//! differing HipYawPitch values): a message naming the input line goes to stderr, nothing more is
//! written, and the program exits with status 1 (status 2 for bad arguments or an unloadable URDF).

use std::io::{BufRead, Write};
use std::process::ExitCode;

use serde_json::{Map, Value, json};
use taskstack::model::{Model, ModelData};
use taskstack::robots::nao;

fn model_for(root: &str) -> Result<Model, String> {
    match root {
        "r_sole" => Ok(nao::rfoot()),
        "l_sole" => Ok(nao::lfoot()),
        "torso" => Ok(nao::torso()),
        _ => match root.strip_prefix("urdf:") {
            Some(path) => nao::from_urdf_file(path, None).map_err(|e| e.to_string()),
            None => Err(format!(
                "unknown root `{root}` (expected r_sole, l_sole, torso or urdf:<path>)"
            )),
        },
    }
}

/// `q` in the model's variable order from a `{"q": {...}}` object.
fn parse_q(model: &Model, line: &str) -> Result<Vec<f64>, String> {
    let value: Value = serde_json::from_str(line).map_err(|e| format!("malformed JSON: {e}"))?;
    let joints = value
        .get("q")
        .and_then(Value::as_object)
        .ok_or("expected an object {\"q\": {joint: value, ...}}")?;
    let mut q = vec![0.0; model.nv()];
    let mut right_hyp = None;
    for (name, v) in joints {
        let x = v
            .as_f64()
            .ok_or_else(|| format!("joint `{name}`: not a number"))?;
        if name == "RHipYawPitch" {
            right_hyp = Some(x);
            continue;
        }
        let k = model
            .variable_index(name)
            .map_err(|_| format!("unknown joint `{name}`"))?;
        q[k] = x;
    }
    if let Some(r) = right_hyp {
        let k = model
            .variable_index("LHipYawPitch")
            .map_err(|e| e.to_string())?;
        if joints.contains_key("LHipYawPitch") && q[k] != r {
            return Err(format!(
                "LHipYawPitch ({}) and RHipYawPitch ({r}) differ: they are one motor",
                q[k]
            ));
        }
        q[k] = r;
    }
    Ok(q)
}

fn frames_json(model: &Model, data: &mut ModelData, q: &[f64]) -> Result<Value, String> {
    model
        .forward_kinematics(data, q)
        .map_err(|e| e.to_string())?;
    let mut frames = Map::new();
    for (frame, placement) in model.frames().iter().zip(data.frame_placements()) {
        let p = placement.translation.vector;
        frames.insert(frame.name.clone(), json!([p.x, p.y, p.z]));
    }
    let com = model.com(data).map_err(|e| e.to_string())?;
    Ok(json!({ "frames": frames, "com": [com.x, com.y, com.z] }))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = match args.as_slice() {
        [] => "r_sole".to_owned(),
        [flag, root] if flag == "--root" => root.clone(),
        [arg] if arg.starts_with("--root=") => arg["--root=".len()..].to_owned(),
        _ => {
            eprintln!("usage: fk [--root r_sole|l_sole|torso|urdf:<path>] < q.jsonl");
            return ExitCode::from(2);
        }
    };
    let model = match model_for(&root) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("fk: {e}");
            return ExitCode::from(2);
        }
    };
    let mut data = model.new_data();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for (number, line) in std::io::stdin().lock().lines().enumerate() {
        let result = line
            .map_err(|e| format!("cannot read stdin: {e}"))
            .and_then(|line| {
                if line.trim().is_empty() {
                    return Ok(None);
                }
                let q = parse_q(&model, &line)?;
                frames_json(&model, &mut data, &q).map(Some)
            });
        match result {
            Ok(None) => {}
            Ok(Some(value)) => {
                if writeln!(out, "{value}").and_then(|_| out.flush()).is_err() {
                    return ExitCode::from(1);
                }
            }
            Err(e) => {
                eprintln!("fk: input line {}: {e}", number + 1);
                return ExitCode::from(1);
            }
        }
    }
    ExitCode::SUCCESS
}
