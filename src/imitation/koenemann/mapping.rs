//! Posture mapping (Koenemann et al. §III–IV.B, eq. 1–5).
//!
//! A posture is the position of each hand relative to its shoulder and of each foot (ankle)
//! relative to its hip, in trunk axes (eq. 1): x forward, y left, z up. For the human, the
//! chest axes for the hands (y along the shoulders, z toward MidShoulder from MidHip) and the
//! pelvis axes for the feet (y along the hips); for the robot, its torso frame.
//!
//! From a reference posture of each (`f_ref,H`, `f_ref,R`) and each limb's length ratio
//! `m = l_limb,R / l_limb,H` (eq. 4), a human posture maps to
//! `f_R = f_ref,R + m · (f_H − f_ref,H)` (eq. 2, 3, 5).
//!
//! The robot's reference is the ideal T-pose for the arms, each stretched sideways at its full
//! length (a robot whose joint limits forbid the T-pose, like the NAO's shoulders, still has
//! one), and its standing posture for the legs (straight legs are singular, and the NAO stands
//! with bent knees). The human's is their first frame when it is a T-pose (the CMU
//! recordings start with one), else the same ideal T-pose at the human's limb lengths (Kinect
//! recordings, whose subjects start with their arms down): with ideal references on both sides
//! the arms' mapping is plain scaling, `f_R = m · f_H`. Limb lengths are the sums of the segments
//! (shoulder → elbow → hand, hip → knee → ankle), measured on the first frame, so a bent arm
//! does not shorten its limb.

use nalgebra::{Matrix3, Vector3};

use crate::human::{HumanFrame, HumanJoint as J, Side};

/// Hands relative to their shoulders and feet (ankles) relative to their hips, in trunk axes
/// (m), `[left, right]` (eq. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Posture {
    /// Hand − shoulder.
    pub hands: [Vector3<f64>; 2],
    /// Ankle − hip.
    pub feet: [Vector3<f64>; 2],
}

impl Posture {
    /// The ideal T-pose of limbs of these lengths: hands at `(0, ±arm, 0)`, feet at
    /// `(0, 0, −leg)` (m).
    pub fn ideal(limbs: &Limbs) -> Self {
        let sideways = |side: Side, length: f64| Vector3::new(0.0, side.pick(length, -length), 0.0);
        Posture {
            hands: Side::BOTH.map(|s| sideways(s, limbs.arms[s.index()])),
            feet: Side::BOTH.map(|s| Vector3::new(0.0, 0.0, -limbs.legs[s.index()])),
        }
    }

    /// The human's posture in `frame` (eq. 1), or `None` when a joint it needs is missing
    /// (a hand falls back to its wrist).
    pub fn of_human(frame: &HumanFrame) -> Option<Self> {
        let up = frame.get(J::MidShoulder)? - frame.get(J::MidHip)?;
        let chest = trunk_axes(frame.get(J::LShoulder)? - frame.get(J::RShoulder)?, up)?;
        let pelvis = trunk_axes(frame.get(J::LHip)? - frame.get(J::RHip)?, up)?;
        let hand = |side: Side| -> Option<Vector3<f64>> {
            let [shoulder, wrist, hand] = side.pick(
                [J::LShoulder, J::LWrist, J::LHand],
                [J::RShoulder, J::RWrist, J::RHand],
            );
            let tip = frame.get(hand).or_else(|| frame.get(wrist))?;
            Some(chest.transpose() * (tip - frame.get(shoulder)?))
        };
        let foot = |side: Side| -> Option<Vector3<f64>> {
            let [hip, ankle] = side.pick([J::LHip, J::LAnkle], [J::RHip, J::RAnkle]);
            Some(pelvis.transpose() * (frame.get(ankle)? - frame.get(hip)?))
        };
        Some(Posture {
            hands: [hand(Side::Left)?, hand(Side::Right)?],
            feet: [foot(Side::Left)?, foot(Side::Right)?],
        })
    }

    /// Whether this is a T-pose: each arm within 30° of straight sideways, each leg within 20°
    /// of straight down.
    pub fn is_t_pose(&self) -> bool {
        let arms = Side::BOTH.iter().all(|&s| {
            let h = self.hands[s.index()];
            s.pick(1.0, -1.0) * h.y >= 30f64.to_radians().cos() * h.norm()
        });
        let legs = (self.feet.iter()).all(|f| -f.z >= 20f64.to_radians().cos() * f.norm());
        arms && legs
    }
}

/// Rotation whose columns are trunk axes: y along `across` (right → left), z toward `up` made
/// orthogonal to it, x = y × z. `None` for degenerate input.
fn trunk_axes(across: Vector3<f64>, up: Vector3<f64>) -> Option<Matrix3<f64>> {
    let y = across.try_normalize(1e-9)?;
    let x = y.cross(&up).try_normalize(1e-9)?;
    Some(Matrix3::from_columns(&[x, y, x.cross(&y)]))
}

/// Limb lengths (m), `[left, right]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limbs {
    /// Shoulder → elbow → hand.
    pub arms: [f64; 2],
    /// Hip → knee → ankle.
    pub legs: [f64; 2],
}

impl Limbs {
    /// The human's limb lengths in `frame` (a hand falls back to its wrist), or `None` when a
    /// joint is missing or a limb has no length.
    pub fn of_human(frame: &HumanFrame) -> Option<Self> {
        let chain = |joints: [J; 3]| -> Option<f64> {
            let [a, b, c] = joints.map(|j| frame.get(j));
            let length = (b? - a?).norm() + (c? - b?).norm();
            (length > 1e-6).then_some(length)
        };
        let hand = |hand: J, wrist: J| {
            if frame.get(hand).is_some() {
                hand
            } else {
                wrist
            }
        };
        Some(Limbs {
            arms: [
                chain([J::LShoulder, J::LElbow, hand(J::LHand, J::LWrist)])?,
                chain([J::RShoulder, J::RElbow, hand(J::RHand, J::RWrist)])?,
            ],
            legs: [
                chain([J::LHip, J::LKnee, J::LAnkle])?,
                chain([J::RHip, J::RKnee, J::RAnkle])?,
            ],
        })
    }
}

/// Which human posture the mapping takes as the human's reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Calibration {
    /// The first frame if it is a T-pose ([`Posture::is_t_pose`]), else the ideal T-pose at
    /// the human's limb lengths. Default.
    #[default]
    Auto,
    /// The first frame, whatever it is (the subject is known to start in the reference pose).
    FirstFrame,
    /// The ideal T-pose at the human's limb lengths: plain limb-ratio scaling.
    Ideal,
}

/// The calibrated map from human to robot postures (eq. 2–5).
#[derive(Debug, Clone, PartialEq)]
pub struct PostureMapping {
    human_reference: Posture,
    robot_reference: Posture,
    /// `m` of eq. 4: arms then legs, `[left, right]` each.
    ratios: Limbs,
    /// Whether the human's reference is their first frame (else the ideal T-pose).
    from_first_frame: bool,
}

impl PostureMapping {
    /// Calibrates on the human's first frame `frame`, for a robot with limbs `robot`; `None`
    /// when the frame lacks a joint the posture needs.
    /// `robot_feet`: the robot's ankles relative to its hips standing (its reference for the
    /// feet: a robot like the NAO stands with bent knees, and straight legs are singular).
    pub fn calibrate(
        frame: &HumanFrame,
        robot: &Limbs,
        robot_feet: [Vector3<f64>; 2],
        calibration: Calibration,
    ) -> Option<Self> {
        let human = Limbs::of_human(frame)?;
        let first = Posture::of_human(frame)?;
        let from_first_frame = match calibration {
            Calibration::Auto => first.is_t_pose(),
            Calibration::FirstFrame => true,
            Calibration::Ideal => false,
        };
        let ratio = |r: [f64; 2], h: [f64; 2]| [r[0] / h[0], r[1] / h[1]];
        Some(PostureMapping {
            human_reference: if from_first_frame {
                first
            } else {
                Posture::ideal(&human)
            },
            robot_reference: Posture {
                feet: robot_feet,
                ..Posture::ideal(robot)
            },
            ratios: Limbs {
                arms: ratio(robot.arms, human.arms),
                legs: ratio(robot.legs, human.legs),
            },
            from_first_frame,
        })
    }

    /// The robot posture for the human posture `human`: `f_ref,R + m (f_H − f_ref,H)`.
    pub fn map(&self, human: &Posture) -> Posture {
        let map =
            |r: Vector3<f64>, h: Vector3<f64>, h_ref: Vector3<f64>, m: f64| r + (h - h_ref) * m;
        let (hr, rr) = (&self.human_reference, &self.robot_reference);
        Posture {
            hands: [0, 1].map(|k| {
                map(
                    rr.hands[k],
                    human.hands[k],
                    hr.hands[k],
                    self.ratios.arms[k],
                )
            }),
            feet: [0, 1].map(|k| map(rr.feet[k], human.feet[k], hr.feet[k], self.ratios.legs[k])),
        }
    }

    /// The limb ratios `m` (eq. 4).
    pub fn ratios(&self) -> &Limbs {
        &self.ratios
    }

    /// Whether the human's reference is their first frame (a T-pose) rather than the ideal one.
    pub fn calibrated_on_first_frame(&self) -> bool {
        self.from_first_frame
    }
}
