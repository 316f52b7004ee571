//! The contact change list of a clip (issue 14, Di Fava et al. eq. 14–15): a synthetic clip
//! whose events are worked out by hand, and the real clip of a person leaning on a stool.

use taskstack::Vector3;
use taskstack::human::{HumanFrame, HumanJoint};
use taskstack::imitation::reference::contact_events::{
    ContactChange, ContactConfig, ContactError, ContactEvent, ContactLink, contact_events,
};
use taskstack::io::clip::Clip;
use taskstack::scene::{Scene, Surface};

const DT: f64 = 0.01;

fn table_scene() -> Scene {
    Scene::new(vec![
        Surface::plane("floor", 0.0).unwrap(),
        // x from 0.3 to 0.7, y from -0.1 to 0.5, top at 0.7 m.
        Surface::rectangle("table", [0.5, 0.2], [0.4, 0.6], 0.0, 0.7).unwrap(),
    ])
    .unwrap()
}

/// Height of the left knuckles at time `t` (the wrist is 1 cm higher):
/// * 0–1.35 s: down from 0.99 m at 0.2 m/s to 0.72 m (joint centre 2 cm above the table);
/// * 1.35–2.35 s: resting, jumping between 0.72 and 0.78 m every 0.1 s (inside the
///   hysteresis band: above the 6 cm entry height, below the 9 cm exit height);
/// * 2.35 s on: up at 0.3 m/s, to 0.9 m;
/// * 3.00–3.10 s: a touch at 0.75 m too short to count (0.1 s < 0.2 s).
fn left_knuckle_height(i: usize) -> f64 {
    let t = i as f64 * DT;
    if (300..310).contains(&i) {
        0.75
    } else if t < 1.35 {
        0.99 - 0.2 * t
    } else if t < 2.35 {
        0.72 + 0.06 * ((i / 10) % 2) as f64
    } else {
        (0.72 + 0.3 * (t - 2.35)).min(0.9)
    }
}

/// The right hand sweeps across the table at 0.73 m at 1 m/s (too fast to land), then rests
/// 0.3 m beyond its edge (too far off it).
fn right_hand_x(i: usize) -> f64 {
    (i as f64 * DT).min(1.0)
}

fn synthetic_clip() -> Vec<HumanFrame> {
    (0..400)
        .map(|i| {
            let mut f = HumanFrame::new(i as f64 * DT);
            let z = left_knuckle_height(i);
            f.set(HumanJoint::LHand, Some(Vector3::new(0.5, 0.2, z)));
            f.set(HumanJoint::LWrist, Some(Vector3::new(0.45, 0.2, z + 0.01)));
            let x = right_hand_x(i);
            f.set(HumanJoint::RHand, Some(Vector3::new(x, 0.2, 0.73)));
            f.set(HumanJoint::RWrist, Some(Vector3::new(x - 0.05, 0.2, 0.74)));
            for (ankle, toe, y) in [
                (HumanJoint::LAnkle, HumanJoint::LToe, 0.1),
                (HumanJoint::RAnkle, HumanJoint::RToe, -0.1),
            ] {
                f.set(ankle, Some(Vector3::new(0.0, y, 0.08)));
                f.set(toe, Some(Vector3::new(0.12, y, 0.04)));
            }
            f
        })
        .collect()
}

#[test]
fn the_hand_placed_on_the_table_enters_and_leaves_once_at_the_hand_worked_times() {
    let scene = table_scene();
    let events = contact_events(&synthetic_clip(), &scene, &ContactConfig::default()).unwrap();
    let summary: Vec<_> = events
        .iter()
        .map(|e| (e.link, scene.surfaces()[e.surface].name(), e.change))
        .collect();
    assert_eq!(
        summary,
        [
            (ContactLink::LeftFoot, "floor", ContactChange::Enter),
            (ContactLink::RightFoot, "floor", ContactChange::Enter),
            (ContactLink::LeftHand, "table", ContactChange::Enter),
            (ContactLink::LeftHand, "table", ContactChange::Leave),
        ],
        "{events:#?}"
    );
    assert_eq!(
        (events[0].frame, events[0].time),
        (0, 0.0),
        "feet on the floor from the start"
    );
    // Enters when the knuckles reach 0.76 m (6 cm up): 0.99 − 0.2·t = 0.76 at t = 1.15 s.
    assert!(
        (events[2].time - 1.15).abs() <= DT + 1e-9,
        "{:?}",
        events[2]
    );
    // Leaves above 0.79 m (9 cm up): 0.72 + 0.3·(t − 2.35) = 0.79 at t = 2.5833 s, the first
    // frame after it at 2.59 s. The jitter up to 0.78 m while resting does not end the contact.
    assert!(
        (events[3].time - 2.59).abs() <= DT + 1e-9,
        "{:?}",
        events[3]
    );
    let frame_of = |e: &ContactEvent| (e.time / DT).round() as usize;
    assert!(events.iter().all(|e| e.frame == frame_of(e)));
}

#[test]
fn without_hysteresis_the_resting_hand_chatters() {
    // The same clip with the exit height at the entry height: each jump up to 0.78 m ends the
    // contact and the hand's return restarts it, five times in the second of rest. Shows that the
    // band above is what keeps the one contact of the first test.
    let mut config = ContactConfig::default();
    config.hands.leave_height = config.hands.enter_height;
    config.min_duration = 0.0;
    let events = contact_events(&synthetic_clip(), &table_scene(), &config).unwrap();
    let hand = events
        .iter()
        .filter(|e| e.link == ContactLink::LeftHand)
        .count();
    assert!(hand >= 10, "{hand} hand events");
}

#[test]
fn a_touch_shorter_than_the_minimum_duration_is_kept_when_the_minimum_is_lowered() {
    let config = ContactConfig {
        min_duration: 0.05,
        ..ContactConfig::default()
    };
    let events = contact_events(&synthetic_clip(), &table_scene(), &config).unwrap();
    let hand: Vec<_> = events
        .iter()
        .filter(|e| e.link == ContactLink::LeftHand)
        .collect();
    // The touch at 3.00–3.10 s: the first frame at 0.75 m comes at 15 m/s (no entry), the next
    // at rest enters at 3.01 s; it leaves at 3.10 s when the hand jumps back to 0.9 m.
    assert_eq!(hand.len(), 4, "{hand:#?}");
    assert!((hand[2].time - 3.01).abs() < 1e-9 && hand[2].change == ContactChange::Enter);
    assert!((hand[3].time - 3.10).abs() < 1e-9 && hand[3].change == ContactChange::Leave);
}

#[test]
fn bad_thresholds_and_times_are_refused() {
    let frames = synthetic_clip();
    let scene = table_scene();
    let mut config = ContactConfig::default();
    config.hands.leave_height = 0.01;
    assert!(matches!(
        contact_events(&frames, &scene, &config),
        Err(ContactError::Config(_))
    ));
    let config = ContactConfig {
        edge_margin: f64::NAN,
        ..ContactConfig::default()
    };
    assert!(matches!(
        contact_events(&frames, &scene, &config),
        Err(ContactError::Config(_))
    ));
    let mut backwards = frames[..3].to_vec();
    backwards[2].time = backwards[1].time;
    assert_eq!(
        contact_events(&backwards, &scene, &ContactConfig::default()),
        Err(ContactError::Time {
            frame: 2,
            time: backwards[2].time
        })
    );
}

#[test]
fn the_person_leaning_on_the_stool_puts_both_hands_on_it_after_standing_up() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/contact");
    let scene = Scene::from_toml_file(format!("{dir}/stool_23_19.toml")).unwrap();
    let clip = Clip::open(format!("{dir}/cmu_23_19_lean_hands_on_stool.bvh")).unwrap();
    let config = ContactConfig::for_capture(clip.capture());
    let frames: Vec<HumanFrame> = clip.map(Result::unwrap).collect();
    let events = contact_events(&frames, &scene, &config).unwrap();
    let stool = scene.index_of("stool").unwrap();
    let floor = scene.index_of("floor").unwrap();
    for link in [ContactLink::LeftFoot, ContactLink::RightFoot] {
        let first = events.iter().find(|e| e.link == link).unwrap();
        assert_eq!(
            (first.surface, first.change, first.frame),
            (floor, ContactChange::Enter, 0)
        );
        // The heels lift as the subject leans; the feet stay on the floor at least until the
        // last 0.15 s of the clip (README.md in tests/data/contact).
        let leaves = events
            .iter()
            .filter(|e| e.link == link && e.change == ContactChange::Leave);
        assert!(leaves.into_iter().all(|e| e.time > 1.7), "{events:#?}");
    }
    for link in [ContactLink::LeftHand, ContactLink::RightHand] {
        let hand: Vec<_> = events.iter().filter(|e| e.link == link).collect();
        // The hands come down on the stool top (wrists at 0.72–0.75 m) once the subject has
        // stood up (1.15 s) and stay there: one entering event each, none with the floor.
        assert_eq!(hand.len(), 1, "{hand:#?}");
        assert_eq!(
            (hand[0].surface, hand[0].change),
            (stool, ContactChange::Enter)
        );
        assert!((1.15..1.4).contains(&hand[0].time), "{:?}", hand[0]);
    }
    assert!(
        events.windows(2).all(|w| w[0].time <= w[1].time),
        "chronological"
    );
}
