//! The task table of a walking frame: what the whole body does while the pattern generator
//! walks it.

use crate::human::Side;
use crate::imitation::phase::SupportPhase;
use crate::imitation::tables::{
    Axes, ComGoal, Gradient, Level, OrientationTarget, PointTarget, Task, TaskTable,
};
use crate::robots::BipedProfile;

/// The walking table of the model rooted at `root` (the stance sole; the sole that last stood
/// alone while both stand), highest priority first:
///
/// 1. **contact**: the other sole's position and orientation as the walk plans them (on the
///    floor, or on its swing path), 6 rows: a sole on the floor does not move. Named as the
///    support phases' contact level, so that a contact-only Newton step ends every frame as it
///    does there (two Gauss–Newton iterations alone left a standing sole up to 1.5e-5 m off;
///    with the step, under 1e-9 m on the bundled clips);
/// 2. **balance**: the CoM's ground point on the generator's CoM;
/// 3. **torso**: the torso's tilt, leaning over the stance hip as the walk plans;
/// 4. **height**: the CoM at the cart-table's height.
///
/// No self-collision level: an inequality level makes the solver hold a joint at its velocity
/// bound for every level (the active set) instead of slowing the whole step (scale to fit), and
/// with it the judge's NAO fell on every walk (16 of 16 runs); without it, 2 of 16 fell. The
/// step envelope keeps the soles apart, and the arms hold the posture of the walk's start (clear
/// of the torso then, as the support phases keep them): on the bundled clips the closest pair
/// stays 9.9 mm apart (margin 10 mm; the metrics report it). At the human's joint angles a
/// forearm went 3 mm into the torso (CMU 07_04).
///
/// Then the paper's gradients (joint limits, joint tracking); while walking the imitator tracks
/// the posture the walk started from, so the arms hold still and follow neither the human's
/// hands nor their joint angles until the walk is over. A hand level below the height drove the
/// legs through their remaining freedom onto their limits (the swing knee straight at −0.092 rad
/// in a few frames on CMU 09_12), and a joint at its limit is held there for every level, so the
/// torso and the CoM height then lost 5° and 2.5 cm. Arms that copy the human while walking wait
/// for a clamping that holds a joint only for the level that pushed it (see the changelog).
pub fn walking_table(root: Side, profile: &BipedProfile) -> TaskTable {
    let free_sole = &profile.foot(root.other()).sole;
    let point = |frame: &str, axes, target| Task::Point {
        frame: frame.to_owned(),
        offset: [0.0; 3],
        axes,
        target,
    };
    let level = Level::of_tasks;
    let mut levels = vec![level(
        "contact",
        vec![
            point(free_sole, Axes::XYZ, PointTarget::Planned),
            Task::Orientation {
                frame: free_sole.clone(),
                target: OrientationTarget::Footstep,
            },
        ],
    )];
    let middle = ComGoal::BetweenPoints {
        support: profile.sole_centre(root),
        other: profile.sole_centre(root.other()),
    };
    levels.push(level("balance", vec![Task::ComXY(middle)]));
    levels.push(level(
        "torso",
        vec![Task::Orientation {
            frame: profile.torso.clone(),
            target: OrientationTarget::Leaning,
        }],
    ));
    levels.push(level("height", vec![Task::ComHeight]));
    TaskTable {
        phase: match root {
            Side::Right => SupportPhase::Right,
            Side::Left => SupportPhase::Left,
        },
        model_root: root,
        levels,
        gradients: Gradient::paper().to_vec(),
        clamping: true,
    }
}
