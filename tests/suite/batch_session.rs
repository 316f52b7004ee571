//! A clip prepared for a run (`batch::ClipSession`): read once, whole when the run needs what
//! comes later; the look-ahead and the hand supports it gives the imitator are those built by
//! hand from the same frames with the readers and planners below it.

use taskstack::batch::{BatchError, ClipSession, ClipSetup, LookAheadLeads, imitate_clip};
use taskstack::human::{CaptureSystem, HumanFrame};
use taskstack::imitation::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::poubel::hand_support::{HandContactPlan, HandSupportConfig};
use taskstack::imitation::reference::contact_events::ContactConfig;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::walking::look_ahead::{FootLookAhead, FootSchedule};
use taskstack::io::clip::Clip;
use taskstack::robots::nao;
use taskstack::scene::Scene;
use taskstack::{Imitator, ImitatorConfig};

const WALK: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_07_04_slow_walk.bvh"
);
const CONTACT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/contact");

fn streamed(path: &str) -> Vec<HumanFrame> {
    Clip::open(path).unwrap().collect::<Result<_, _>>().unwrap()
}

#[test]
fn a_clip_read_whole_replays_what_the_file_streams() {
    let frames = streamed(WALK);
    assert!(frames.len() > 100);
    let streaming = Clip::open(WALK).unwrap();
    assert!(streaming.frames_ahead().is_none());
    let mut whole = streaming.read_whole().unwrap();
    assert_eq!(whole.frames_ahead().unwrap(), &frames[..]);
    assert_eq!(whole.declared_frames(), Some(frames.len() as u64));
    let mut first = HumanFrame::new(-1.0);
    assert!(whole.read_frame(&mut first).unwrap());
    assert_eq!(first, frames[0]);
    assert_eq!(whole.frames_ahead().unwrap().len(), frames.len() - 1);
    let rest: Vec<HumanFrame> = whole.collect::<Result<_, _>>().unwrap();
    assert_eq!(rest, frames[1..]);
}

#[test]
fn an_online_session_streams_and_sets_the_capture_systems_support() {
    let base = ImitatorConfig {
        support: SupportConfig::for_capture(CaptureSystem::DepthCamera),
        ..ImitatorConfig::default()
    };
    let session = ClipSession::open(WALK.as_ref(), &ClipSetup::default()).unwrap();
    assert!(session.clip().frames_ahead().is_none(), "read as it goes");
    let config = session.config(&base).unwrap();
    assert_eq!(
        config.support,
        SupportConfig::for_capture(CaptureSystem::Optical)
    );
    let poubel = config.poubel().unwrap();
    assert!(poubel.look_ahead.is_none() && poubel.hand_supports.is_none());
}

#[test]
fn an_offline_session_knows_the_foot_lifts_and_runs_as_built_by_hand() {
    let leads = LookAheadLeads {
        lift_lead: 1.2,
        landing_lead: 0.6,
    };
    let setup = ClipSetup {
        look_ahead: Some(leads),
        ..ClipSetup::default()
    };
    let session = ClipSession::open(WALK.as_ref(), &setup).unwrap();
    let config = session.config(&ImitatorConfig::default()).unwrap();
    let frames = streamed(WALK);
    let support = SupportConfig::for_capture(CaptureSystem::Optical);
    let by_hand = FootLookAhead {
        schedule: FootSchedule::of_clip(&frames, support).unwrap(),
        lift_lead: 1.2,
        landing_lead: 0.6,
    };
    let poubel = config.poubel().unwrap();
    assert_eq!(poubel.look_ahead.as_ref(), Some(&by_hand));
    assert!(!by_hand.schedule.lifts(taskstack::Side::Left).is_empty());

    // The session's run and the run of the look-ahead built by hand give the same targets.
    let run = |clip: Clip, config: ImitatorConfig| {
        let mut imitator = Imitator::new(nao::profile(), config).unwrap();
        let mut targets = Vec::new();
        imitate_clip(WALK.as_ref(), clip, &mut imitator, 1.0, |f| {
            targets.extend_from_slice(&f.servo_targets)
        })
        .unwrap();
        targets
    };
    let hand_config = ImitatorConfig {
        support,
        method: ImitationMethod::Poubel(PoubelConfig {
            look_ahead: Some(by_hand),
            ..PoubelConfig::default()
        }),
        ..ImitatorConfig::default()
    };
    assert_eq!(
        run(session.into_clip(), config),
        run(Clip::open(WALK).unwrap(), hand_config)
    );
}

#[test]
fn a_session_with_a_scene_plans_the_hand_contacts() {
    let clip = format!("{CONTACT}/cmu_23_19_lean_hands_on_stool.bvh");
    let scene = Scene::from_toml_file(format!("{CONTACT}/stool_23_19.toml")).unwrap();
    let setup = ClipSetup {
        scene: Some(scene.clone()),
        ..ClipSetup::default()
    };
    let session = ClipSession::open(clip.as_ref(), &setup).unwrap();
    let frames = streamed(&clip);
    let contacts = ContactConfig::for_capture(CaptureSystem::Optical);
    let plan = HandContactPlan::of_clip(&frames, &scene, &contacts).unwrap();
    let config = session.config(&ImitatorConfig::default()).unwrap();
    let poubel = config.poubel().unwrap();
    assert_eq!(poubel.hand_supports, Some(HandSupportConfig::new(plan)));
    assert!(poubel.look_ahead.is_none());
    assert_eq!(session.clip().frames_ahead().unwrap(), &frames[..]);
}

#[test]
fn a_session_on_a_missing_clip_is_an_error_naming_it() {
    let setup = ClipSetup {
        look_ahead: Some(LookAheadLeads::default()),
        ..ClipSetup::default()
    };
    let err = ClipSession::open("nowhere/missing.bvh".as_ref(), &setup).unwrap_err();
    assert!(matches!(err, BatchError::Clip { .. }), "{err:?}");
    assert!(err.to_string().contains("missing.bvh"), "{err}");
}

#[test]
fn an_offline_session_refuses_koenemanns_method_naming_the_clip() {
    let setup = ClipSetup {
        look_ahead: Some(LookAheadLeads::default()),
        ..ClipSetup::default()
    };
    let session = ClipSession::open(WALK.as_ref(), &setup).unwrap();
    let koenemann = ImitatorConfig {
        method: ImitationMethod::Koenemann(KoenemannConfig::default()),
        ..ImitatorConfig::default()
    };
    let err = session.config(&koenemann).unwrap_err();
    assert!(
        matches!(err, BatchError::NeedsPoubel { what, .. } if what.contains("look-ahead")),
        "{err:?}"
    );
    assert!(err.to_string().contains("cmu_07_04_slow_walk.bvh"), "{err}");
}
