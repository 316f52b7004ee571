//! The DH table loader (`model::dh`): each malformed table is rejected with an error naming the
//! origin, the row and the field.

use taskstack::model::Model;
use taskstack::model::dh::{DhError, DhProblem};

const PLANAR: &str = include_str!("../data/planar3r.toml");
const ORIGIN: &str = "tests/data/planar3r.toml";

/// The planar table with the first `from` after `anchor` replaced by `to`.
fn edited(anchor: &str, from: &str, to: &str) -> String {
    let start = PLANAR.find(anchor).expect("anchor") + anchor.len();
    let at = start + PLANAR[start..].find(from).expect("from");
    format!("{}{}{}", &PLANAR[..at], to, &PLANAR[at + from.len()..])
}

/// Loads `text`, expects an `Invalid` error at `place`/`field`, returns its problem.
fn rejected(text: &str, place: &str, field: &str) -> DhProblem {
    let err = Model::from_dh_str(text, ORIGIN).expect_err("must be rejected");
    let message = err.to_string();
    assert!(message.starts_with(ORIGIN), "{message}");
    match err {
        DhError::Invalid {
            place: p,
            field: f,
            problem,
            ..
        } => {
            assert_eq!((p.as_str(), f.as_str()), (place, field), "{message}");
            assert!(
                message.contains(place) && message.contains(field),
                "{message}"
            );
            problem
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn the_unedited_table_loads() {
    let model = Model::from_dh_str(PLANAR, ORIGIN).unwrap();
    assert_eq!(
        (model.nv(), model.links().len(), model.frames().len()),
        (3, 4, 1)
    );
}

#[test]
fn missing_field() {
    let text = edited("name = \"J2\"", "mass = 2.0\n", "");
    assert_eq!(
        rejected(&text, "joints[1] (J2)", "mass"),
        DhProblem::Missing
    );
}

#[test]
fn missing_variable_on_a_revolute_joint() {
    let text = edited("name = \"J2\"", "variable = \"q2\"\n", "");
    assert_eq!(
        rejected(&text, "joints[1] (J2)", "variable"),
        DhProblem::Missing
    );
}

#[test]
fn unknown_antecedent() {
    let text = edited(
        "name = \"J3\"",
        "antecedent = \"L2\"",
        "antecedent = \"L9\"",
    );
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "antecedent"),
        DhProblem::UnknownAntecedent("L9".into())
    );
}

#[test]
fn cycle() {
    // J2 hangs from L3 and J3 from L2: neither reaches the base.
    let text = edited(
        "name = \"J2\"",
        "antecedent = \"L1\"",
        "antecedent = \"L3\"",
    );
    assert_eq!(
        rejected(&text, "joints[1] (J2)", "antecedent"),
        DhProblem::Cycle("L3".into())
    );
}

#[test]
fn duplicate_joint_name() {
    let text = edited("name = \"J2\"", "name = \"J3\"", "name = \"J2\"");
    assert_eq!(
        rejected(&text, "joints[2] (J2)", "name"),
        DhProblem::Duplicate("J2".into())
    );
}

#[test]
fn duplicate_link_name() {
    let text = edited("name = \"J3\"", "link = \"L3\"", "link = \"ground\"");
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "link"),
        DhProblem::Duplicate("ground".into())
    );
}

#[test]
fn non_finite_number() {
    let text = edited("name = \"J2\"", "d = 0.3", "d = nan");
    assert!(
        matches!(rejected(&text, "joints[1] (J2)", "d"), DhProblem::NonFinite(x) if x.is_nan())
    );
    let text = edited(
        "name = \"tip\"",
        "position = [0.1, 0.0, 0.0]",
        "position = [0.1, inf, 0.0]",
    );
    assert_eq!(
        rejected(&text, "frames[0] (tip)", "position"),
        DhProblem::NonFinite(f64::INFINITY)
    );
}

#[test]
fn negative_mass() {
    let text = edited("name = \"J3\"", "mass = 1.0", "mass = -1.0");
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "mass"),
        DhProblem::Negative(-1.0)
    );
    let text = edited("[base]", "mass = 0.0", "mass = -0.5");
    assert_eq!(rejected(&text, "base", "mass"), DhProblem::Negative(-0.5));
}

#[test]
fn unknown_variable() {
    let text = edited("name = \"J3\"", "variable = \"q3\"", "variable = \"q9\"");
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "variable"),
        DhProblem::UnknownVariable("q9".into())
    );
}

#[test]
fn unused_variable() {
    let text = edited("name = \"J3\"", "variable = \"q3\"", "variable = \"q2\"");
    assert_eq!(
        rejected(&text, "variables[2] (q3)", "name"),
        DhProblem::UnusedVariable("q3".into())
    );
}

#[test]
fn lower_above_upper() {
    let text = edited("name = \"q1\"", "lower = -3.0", "lower = 4.0");
    assert_eq!(
        rejected(&text, "variables[0] (q1)", "upper"),
        DhProblem::LowerAboveUpper {
            lower: 4.0,
            upper: 3.0
        }
    );
}

#[test]
fn wrong_units() {
    let text = edited("[units]", "length = \"m\"", "length = \"mm\"");
    assert_eq!(
        rejected(&text, "units", "length"),
        DhProblem::WrongUnit {
            expected: "m",
            got: "mm".into()
        }
    );
    let text = edited("[units]", "angle = \"rad\"", "angle = \"deg\"");
    assert_eq!(
        rejected(&text, "units", "angle"),
        DhProblem::WrongUnit {
            expected: "rad",
            got: "deg".into()
        }
    );
}

#[test]
fn wrong_format_unknown_field_wrong_type_fixed_with_variable() {
    let text = PLANAR.replace("taskstack-dh/1", "taskstack-dh/2");
    assert_eq!(
        rejected(&text, "document", "format"),
        DhProblem::WrongFormat("taskstack-dh/2".into())
    );
    let text = edited("name = \"J2\"", "mass = 2.0", "mas = 2.0");
    assert_eq!(
        rejected(&text, "joints[1] (J2)", "mas"),
        DhProblem::UnknownField
    );
    let text = edited("name = \"J2\"", "d = 0.3", "d = \"0.3\"");
    assert_eq!(
        rejected(&text, "joints[1] (J2)", "d"),
        DhProblem::WrongType("a number")
    );
    let text = edited("name = \"J3\"", "type = \"revolute\"", "type = \"fixed\"");
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "variable"),
        DhProblem::VariableOnFixed
    );
    let text = edited(
        "name = \"J3\"",
        "type = \"revolute\"",
        "type = \"spherical\"",
    );
    assert_eq!(
        rejected(&text, "joints[2] (J3)", "type"),
        DhProblem::UnknownJointType("spherical".into())
    );
}

#[test]
fn syntax_errors_and_files_name_their_origin() {
    let err =
        Model::from_dh_str("format = \"taskstack-dh/1\"\n[units\n", "<embedded>").unwrap_err();
    assert!(
        matches!(err, DhError::Syntax { ref origin, .. } if origin == "<embedded>"),
        "{err}"
    );
    assert!(
        err.to_string().contains("line 2") || err.to_string().contains("2:"),
        "{err}"
    );
    let err = Model::from_dh_file("tests/data/no_such_table.toml").unwrap_err();
    assert!(
        matches!(err, DhError::Io { ref origin, .. } if origin == "tests/data/no_such_table.toml")
    );
    let model = Model::from_dh_file("robots/nao_dh/nao_rfoot.toml").unwrap();
    assert_eq!(model.nv(), 23);
}
