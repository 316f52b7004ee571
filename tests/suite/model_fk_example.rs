//! The `fk` example's JSON-lines contract, run as a process. `cargo test` builds the
//! examples next to the test binaries (`target/<profile>/examples/`).

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::Value;

fn run_fk(root: &str, input: &str) -> (i32, String, String) {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().parent().unwrap();
    let fk = dir
        .join("examples")
        .join(format!("fk{}", std::env::consts::EXE_SUFFIX));
    let mut child = Command::new(fk)
        .args(["--root", root])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the fk example is built by cargo test");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

const POSE: &str = r#"{"q": {"HeadYaw": 0.3, "LShoulderPitch": 1.4, "LElbowRoll": -1.0, "LHipYawPitch": -0.2, "RHipYawPitch": -0.2, "RKneePitch": 0.7}}"#;

#[test]
fn dh_torso_and_urdf_roots_print_the_same_frames() {
    let (code_dh, dh, _) = run_fk("torso", &format!("{POSE}\n\n{{\"q\": {{}}}}\n"));
    let (code_urdf, urdf, _) = run_fk(
        "urdf:tests/data/nao.urdf",
        &format!("{POSE}\n{{\"q\": {{}}}}\n"),
    );
    assert_eq!((code_dh, code_urdf), (0, 0));
    let (dh, urdf): (Vec<&str>, Vec<&str>) = (dh.lines().collect(), urdf.lines().collect());
    assert_eq!((dh.len(), urdf.len()), (2, 2));
    for (a, b) in dh.iter().zip(&urdf) {
        let (a, b): (Value, Value) = (
            serde_json::from_str(a).unwrap(),
            serde_json::from_str(b).unwrap(),
        );
        let frames = a["frames"].as_object().unwrap();
        assert_eq!(frames.len(), 23);
        for (name, pa) in frames {
            for k in 0..3 {
                let (x, y) = (
                    pa[k].as_f64().unwrap(),
                    b["frames"][name][k].as_f64().unwrap(),
                );
                assert!((x - y).abs() < 1e-9, "{name}");
            }
        }
        for k in 0..3 {
            assert!((a["com"][k].as_f64().unwrap() - b["com"][k].as_f64().unwrap()).abs() < 1e-9);
        }
    }
    // Second line, q = 0, torso root: the head is NeckOffsetZ 0.1265 above the torso.
    let zero: Value = serde_json::from_str(dh[1]).unwrap();
    assert!((zero["frames"]["head"][2].as_f64().unwrap() - 0.1265).abs() < 1e-12);
}

#[test]
fn sole_root_puts_the_sole_at_the_origin() {
    let (code, out, _) = run_fk("l_sole", "{\"q\": {}}\n");
    assert_eq!(code, 0);
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    // At q = 0 the right sole is 2 × HipOffsetY = 0.1 m to the right of the left sole.
    assert!((v["frames"]["r_sole"][1].as_f64().unwrap() + 0.1).abs() < 1e-12);
}

#[test]
fn bad_input_is_an_error_naming_the_line() {
    let (code, out, err) = run_fk(
        "r_sole",
        "{\"q\": {}}\n{\"q\": {\"LHipYawPitch\": 0.1, \"RHipYawPitch\": 0.2}}\n",
    );
    assert_eq!(code, 1);
    assert_eq!(out.lines().count(), 1);
    assert!(
        err.contains("line 2") && err.contains("RHipYawPitch"),
        "{err}"
    );
    let (code, _, err) = run_fk("r_sole", "{\"q\": {\"LHand\": 0.5}}\n");
    assert_eq!(code, 1);
    assert!(err.contains("unknown joint `LHand`"), "{err}");
    let (code, _, _) = run_fk("pelvis", "");
    assert_eq!(code, 2);
}
