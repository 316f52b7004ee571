//! Parsers under attack (issue 6, item 1): the BVH reader, the Kinect CSV reader, the DH table
//! loader and the URDF loader fed mutated copies of the REAL files of the crate (the CMU clips and
//! Kinect recordings in `tests/data/mocap/`, the NAO DH tables in `robots/nao_dh/`, the NAO URDF
//! in `tests/data/nao.urdf`).
//!
//! Mutations: bit flips, truncation at a random point (and, for the small inputs, at every point
//! of the header), duplicated and removed lines, huge (`1e308`, `1e400`), tiny and non-finite
//! (`nan`, `inf`) numbers substituted for numbers of the file, random bytes spliced in. Every case
//! must either parse to a valid value (frames with finite positions and times; models with ordered
//! limits, finite mass and finite forward kinematics) or return a typed error: a panic fails the
//! test, and a hang or an out-of-memory would stop it. The caps (a BVH header claiming 10^12
//! frames or a million joints, a 10 MB Kinect line) have targeted tests that also measure the
//! largest single heap allocation the reader makes (a counting global allocator, per thread).
//!
//! To keep CI short the big files are cut to their header plus the first frames before mutating,
//! and each property runs a few hundred cases (a few thousand in all, a few seconds in release).
//! A long run:
//!
//! ```text
//! PROPTEST_CASES=100000 cargo test --release --test hardening_parsers
//! ```

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::{BufReader, Cursor, Read};
use std::sync::OnceLock;

use proptest::prelude::*;
use taskstack::human::HumanFrame;
use taskstack::io::bvh::{BvhConfig, BvhError, BvhReader};
use taskstack::io::kinect::{KinectConfig, KinectError, KinectReader};
use taskstack::model::{Model, UrdfOptions};
use taskstack::robots::nao;

// ---------------------------------------------------------------------------------------------
// Largest single allocation, per thread (tests run on several threads at once).

struct Counting;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    // `try_with`: the thread-local may already be gone while a thread shuts down.
    let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
}

// SAFETY: forwards every call unchanged to the system allocator; only records sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` and returns its result with the largest single allocation (bytes) it made.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|l| l.set(0));
    let out = f();
    (out, LARGEST.with(Cell::get))
}

// ---------------------------------------------------------------------------------------------
// Inputs: the real files, the big ones cut to their header and first frames.

const MOCAP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");
const FRAMES_KEPT: usize = 50;

fn read(path: &str) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Header and the first `FRAMES_KEPT` frames of a BVH clip, `Frames:` rewritten to match, so that
/// the unmutated slice parses completely.
fn bvh_slice(name: &str) -> Vec<u8> {
    let text = String::from_utf8(read(&format!("{MOCAP}{name}"))).expect("UTF-8 clip");
    let mut out = String::new();
    let mut frames_left = None;
    for line in text.lines() {
        match frames_left {
            Some(0) => break,
            Some(ref mut n) => *n -= 1,
            None if line.starts_with("Frames:") => {
                out.push_str(&format!("Frames: {FRAMES_KEPT}\n"));
                continue;
            }
            None if line.starts_with("Frame Time:") => frames_left = Some(FRAMES_KEPT),
            None => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    out.into_bytes()
}

/// The first frames of a Kinect recording.
fn kinect_slice(name: &str) -> Vec<u8> {
    let text = read(&format!("{MOCAP}{name}"));
    let mut lines = 0;
    let end = text
        .iter()
        .position(|&b| {
            lines += usize::from(b == b'\n');
            lines == FRAMES_KEPT
        })
        .map_or(text.len(), |i| i + 1);
    text[..end].to_vec()
}

struct Inputs {
    bvh: Vec<Vec<u8>>,
    kinect: Vec<Vec<u8>>,
    dh: Vec<Vec<u8>>,
    urdf: Vec<u8>,
}

fn inputs() -> &'static Inputs {
    static INPUTS: OnceLock<Inputs> = OnceLock::new();
    INPUTS.get_or_init(|| Inputs {
        // One CMU-MB and one CMU-MAX skeleton.
        bvh: [
            "cmu_07_04_slow_walk.bvh",
            "cmu_131_01_start_walk_stop_maxskel.bvh",
        ]
        .map(bvh_slice)
        .to_vec(),
        kinect: [
            "kinect2_labanotation_ges01_wavehand.csv",
            "kinect2_labanotation_ges02_balancinghands.csv",
        ]
        .map(kinect_slice)
        .to_vec(),
        dh: [nao::RFOOT_DH, nao::LFOOT_DH, nao::TORSO_DH]
            .map(|t| t.as_bytes().to_vec())
            .to_vec(),
        urdf: read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/nao.urdf")),
    })
}

// ---------------------------------------------------------------------------------------------
// Mutations.

/// Texts substituted for a number of the file.
const NUMBERS: [&str; 14] = [
    "1e308",
    "-1e308",
    "1e400",
    "-1e400",
    "1e-400",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "infinity",
    "18446744073709551616",
    "1000000000000",
    "-0",
    "",
];

#[derive(Debug, Clone)]
enum Mutation {
    FlipBit { at: usize, bit: u8 },
    Truncate { at: usize },
    DuplicateLine { line: usize },
    RemoveLine { line: usize },
    Number { index: usize, text: &'static str },
    Splice { at: usize, bytes: Vec<u8> },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::FlipBit { at, bit }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        any::<usize>().prop_map(|line| Mutation::DuplicateLine { line }),
        any::<usize>().prop_map(|line| Mutation::RemoveLine { line }),
        (any::<usize>(), proptest::sample::select(&NUMBERS[..]))
            .prop_map(|(index, text)| Mutation::Number { index, text }),
        (
            any::<usize>(),
            proptest::collection::vec(any::<u8>(), 1..16)
        )
            .prop_map(|(at, bytes)| Mutation::Splice { at, bytes }),
    ]
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    proptest::collection::vec(mutation(), 1..5)
}

/// Byte ranges of the lines (each including its `\n`).
fn line_ranges(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut ranges = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            ranges.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < bytes.len() {
        ranges.push((start, bytes.len()));
    }
    ranges
}

/// Byte ranges of the numbers: a digit run (with `.`, `e`, `+`, `-`) not glued to a word.
fn number_ranges(bytes: &[u8]) -> Vec<(usize, usize)> {
    let numeric = |b: u8| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-');
    let mut ranges = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let glued = i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        let starts = bytes[i].is_ascii_digit()
            || (matches!(bytes[i], b'-' | b'.')
                && bytes.get(i + 1).is_some_and(|b| b.is_ascii_digit()));
        if starts && !glued {
            let end = (i..bytes.len())
                .find(|&k| !numeric(bytes[k]))
                .unwrap_or(bytes.len());
            ranges.push((i, end));
            i = end;
        } else {
            i += 1;
        }
    }
    ranges
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    match m {
        Mutation::FlipBit { at, bit } if !bytes.is_empty() => {
            let at = at % bytes.len();
            bytes[at] ^= 1 << bit;
        }
        Mutation::Truncate { at } => bytes.truncate(at % (bytes.len() + 1)),
        Mutation::DuplicateLine { line } | Mutation::RemoveLine { line } => {
            let lines = line_ranges(bytes);
            if lines.is_empty() {
                return;
            }
            let (s, e) = lines[line % lines.len()];
            if matches!(m, Mutation::DuplicateLine { .. }) {
                let copy = bytes[s..e].to_vec();
                bytes.splice(e..e, copy);
            } else {
                bytes.drain(s..e);
            }
        }
        Mutation::Number { index, text } => {
            let numbers = number_ranges(bytes);
            if numbers.is_empty() {
                return;
            }
            let (s, e) = numbers[index % numbers.len()];
            bytes.splice(s..e, text.bytes());
        }
        Mutation::Splice { at, bytes: new } => {
            let at = at % (bytes.len() + 1);
            bytes.splice(at..at, new.iter().copied());
        }
        Mutation::FlipBit { .. } => {}
    }
}

fn mutated(original: &[u8], ms: &[Mutation]) -> Vec<u8> {
    let mut bytes = original.to_vec();
    for m in ms {
        apply(&mut bytes, m);
    }
    bytes
}

// ---------------------------------------------------------------------------------------------
// What "valid" means for each parser.

fn check_frame(frame: &HumanFrame, previous_time: Option<f64>) -> Result<(), String> {
    if !frame.time.is_finite() || frame.time < 0.0 {
        return Err(format!("frame time {}", frame.time));
    }
    if previous_time.is_some_and(|t| frame.time < t) {
        return Err(format!("time goes back to {}", frame.time));
    }
    for (joint, p) in frame.joints() {
        if p.is_some_and(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(format!("{joint:?} at {p:?}"));
        }
    }
    Ok(())
}

/// Reads every frame; `Ok(frames)` or the first error. Panics (fails the test) on an invalid frame.
fn read_bvh(bytes: &[u8]) -> Result<usize, BvhError> {
    let reader = BvhReader::new(Cursor::new(bytes), "fuzz.bvh", BvhConfig::cmu())?;
    let max_frames = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
    let mut previous = None;
    let mut count = 0;
    for frame in reader {
        let frame = frame?;
        check_frame(&frame, previous).unwrap_or_else(|e| panic!("BVH frame {count}: {e}"));
        previous = Some(frame.time);
        count += 1;
        assert!(count <= max_frames, "more frames than lines");
    }
    Ok(count)
}

fn read_kinect(bytes: &[u8]) -> Result<usize, KinectError> {
    let reader = KinectReader::new(Cursor::new(bytes), "fuzz.csv", KinectConfig::default());
    let max_frames = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
    let mut previous = None;
    let mut count = 0;
    for frame in reader {
        let frame = frame?;
        check_frame(&frame, previous).unwrap_or_else(|e| panic!("Kinect frame {count}: {e}"));
        previous = Some(frame.time);
        count += 1;
        assert!(count <= max_frames, "more frames than lines");
    }
    Ok(count)
}

/// A loaded model must have usable limits, a finite mass, and finite kinematics inside its limits.
fn check_model(model: &Model) {
    for v in model.variables() {
        assert!(
            !v.lower.is_nan() && !v.upper.is_nan() && v.lower <= v.upper,
            "variable {}: limits [{}, {}]",
            v.name,
            v.lower,
            v.upper
        );
        assert!(
            v.velocity >= 0.0,
            "variable {}: velocity {}",
            v.name,
            v.velocity
        );
    }
    let mass = model.total_mass();
    assert!(mass.is_finite() && mass >= 0.0, "total mass {mass}");
    let mut data = model.new_data();
    // Two configurations inside the limits: 0 clamped into them, and each limit's finite end.
    let zero: Vec<f64> = model
        .variables()
        .iter()
        .map(|v| 0.0_f64.clamp(v.lower, v.upper))
        .collect();
    let edge: Vec<f64> = model
        .variables()
        .iter()
        .map(|v| {
            if v.upper.is_finite() {
                v.upper
            } else {
                v.lower.max(-1.0)
            }
        })
        .map(|x| if x.is_finite() { x } else { 1.0 })
        .collect();
    for q in [zero, edge] {
        model
            .forward_kinematics(&mut data, &q)
            .expect("FK of a q within the limits");
        for (f, p) in model.frames().iter().zip(data.frame_placements()) {
            assert!(
                p.translation.vector.iter().all(|c| c.is_finite())
                    && p.rotation.matrix().iter().all(|c| c.is_finite()),
                "frame {} not finite: {p:?}",
                f.name
            );
        }
        if let Ok(c) = model.com(&data) {
            assert!(c.iter().all(|c| c.is_finite()), "CoM {c:?}");
        }
    }
}

fn load_dh(bytes: &[u8]) -> bool {
    let text = String::from_utf8_lossy(bytes);
    match Model::from_dh_str(&text, "fuzz.toml") {
        Ok(model) => {
            check_model(&model);
            true
        }
        Err(e) => {
            // The message names the origin.
            assert!(e.to_string().starts_with("fuzz.toml"), "{e}");
            false
        }
    }
}

fn load_urdf(bytes: &[u8]) -> bool {
    let text = String::from_utf8_lossy(bytes);
    match Model::from_urdf_str(&text, &UrdfOptions::default()) {
        Ok(model) => {
            check_model(&model);
            true
        }
        Err(e) => {
            assert!(!e.to_string().is_empty());
            false
        }
    }
}

/// Cases per property: `PROPTEST_CASES` if set, else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

// ---------------------------------------------------------------------------------------------
// The unmutated inputs are valid: otherwise the fuzzing would only ever test error paths.

#[test]
fn unmutated_inputs_parse() {
    let inputs = inputs();
    for bvh in &inputs.bvh {
        assert_eq!(read_bvh(bvh).expect("slice parses"), FRAMES_KEPT);
    }
    for csv in &inputs.kinect {
        assert_eq!(read_kinect(csv).expect("slice parses"), FRAMES_KEPT);
    }
    for dh in &inputs.dh {
        assert!(load_dh(dh));
    }
    assert!(load_urdf(&inputs.urdf));
}

// ---------------------------------------------------------------------------------------------
// Truncation at every point of the small inputs' headers.

#[test]
fn bvh_truncated_at_every_byte_of_the_header() {
    for bvh in &inputs().bvh {
        let header_end = bvh
            .windows(11)
            .position(|w| w == b"Frame Time:")
            .expect("has a header");
        // Header plus two frames.
        let end = line_ranges(bvh)
            .into_iter()
            .map(|(_, e)| e)
            .filter(|&e| e > header_end)
            .nth(2)
            .unwrap_or(bvh.len());
        for at in 0..=end {
            // Every cut inside the header or a frame is an error: the slice declares 50 frames.
            assert!(read_bvh(&bvh[..at]).is_err(), "cut at {at} parsed");
        }
    }
}

#[test]
fn kinect_truncated_at_every_byte_of_two_lines() {
    for csv in &inputs().kinect {
        let lines = line_ranges(csv);
        let end = lines[1].1;
        for at in 0..=end {
            let whole_lines = lines.iter().filter(|&&(_, e)| e <= at).count();
            match read_kinect(&csv[..at]) {
                // A cut inside the last number of a line leaves a shorter, valid number.
                Ok(n) => assert!(n == whole_lines || n == whole_lines + 1, "cut at {at}: {n}"),
                // A cut line is a field-count or value error, never a panic.
                Err(KinectError::FieldCount { .. } | KinectError::Value { .. }) => {}
                Err(e) => panic!("cut at {at}: unexpected {e}"),
            }
        }
    }
}

#[test]
fn dh_truncated_at_every_byte_of_the_header_and_every_line() {
    for dh in &inputs().dh {
        // Every byte up to the end of the first variable row, then every line boundary.
        let first_rows = dh
            .windows(9)
            .position(|w| w == b"velocity ")
            .expect("has variables")
            + 32;
        let cuts = (0..first_rows).chain(line_ranges(dh).into_iter().map(|(_, e)| e));
        for at in cuts {
            // A cut at a row boundary may well load (a smaller tree: e.g. the base alone);
            // whatever loads must pass `check_model`, whatever does not must name the origin.
            load_dh(&dh[..at]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Random mutations.

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(800)))]

    #[test]
    fn bvh_survives_mutation(file in 0usize..2, ms in mutations()) {
        let bytes = mutated(&inputs().bvh[file], &ms);
        let _ = read_bvh(&bytes);
    }

    #[test]
    fn kinect_survives_mutation(file in 0usize..2, ms in mutations()) {
        let bytes = mutated(&inputs().kinect[file], &ms);
        let _ = read_kinect(&bytes);
    }

    #[test]
    fn dh_survives_mutation(file in 0usize..3, ms in mutations()) {
        let bytes = mutated(&inputs().dh[file], &ms);
        load_dh(&bytes);
    }

    #[test]
    fn bvh_survives_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        prop_assert!(read_bvh(&bytes).is_err());
    }

    #[test]
    fn kinect_survives_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        // Random bytes are not 101 comma-separated numbers (a blank-only input is zero frames).
        prop_assert_eq!(read_kinect(&bytes).unwrap_or(0), 0);
    }
}

proptest! {
    // The URDF is 70 KB and parsed whole by urdf-rs: fewer cases.
    #![proptest_config(ProptestConfig::with_cases(cases(200)))]

    #[test]
    fn urdf_survives_mutation(ms in mutations()) {
        let bytes = mutated(&inputs().urdf, &ms);
        load_urdf(&bytes);
    }

    #[test]
    fn dh_and_urdf_survive_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        prop_assert!(!load_dh(&bytes));
        prop_assert!(!load_urdf(&bytes));
    }
}

// ---------------------------------------------------------------------------------------------
// Caps: what a file may ask for.

/// A reader producing `prefix`, then `body` repeated `count` times, then `suffix`, without holding
/// the whole text in memory.
struct Generated {
    parts: Vec<(Vec<u8>, u64)>,
    part: usize,
    offset: usize,
    left: u64,
}

impl Generated {
    fn new(parts: Vec<(Vec<u8>, u64)>) -> Self {
        let left = parts.first().map_or(0, |p| p.1);
        Generated {
            parts,
            part: 0,
            offset: 0,
            left,
        }
    }
}

impl Read for Generated {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            let Some((bytes, _)) = self.parts.get(self.part) else {
                return Ok(0);
            };
            if self.left == 0 || bytes.is_empty() {
                self.part += 1;
                self.offset = 0;
                self.left = self.parts.get(self.part).map_or(0, |p| p.1);
                continue;
            }
            let n = (bytes.len() - self.offset).min(buf.len());
            buf[..n].copy_from_slice(&bytes[self.offset..self.offset + n]);
            self.offset += n;
            if self.offset == bytes.len() {
                self.offset = 0;
                self.left -= 1;
            }
            return Ok(n);
        }
    }
}

const ONE_JOINT_BVH: &str = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\n";

#[test]
fn bvh_claiming_1e12_frames_reads_what_is_there_without_reserving() {
    let text = format!("{ONE_JOINT_BVH}Frames: 1000000000000\nFrame Time: 0.01\n1 2 3\n4 5 6\n");
    let config = BvhConfig {
        names: taskstack::io::bvh::BvhNames::Custom(vec![(
            "Hips".into(),
            taskstack::human::HumanJoint::Pelvis,
        )]),
        ..BvhConfig::cmu()
    };
    let (frames, largest) = largest_allocation(|| {
        let reader = BvhReader::new(Cursor::new(text.as_bytes()), "big.bvh", config).unwrap();
        assert_eq!(reader.declared_frames(), 1_000_000_000_000);
        reader.collect::<Vec<_>>()
    });
    assert_eq!(frames.len(), 3, "two frames, then the truncation error");
    assert!(frames[..2].iter().all(Result::is_ok));
    assert!(matches!(
        frames[2],
        Err(BvhError::TruncatedMotion {
            declared: 1_000_000_000_000,
            found: 2,
            ..
        })
    ));
    assert!(largest < 64 * 1024, "largest allocation {largest} B");
}

#[test]
fn bvh_with_a_million_nested_joints_is_refused_at_the_cap() {
    let joint = b" JOINT j\n {\n  OFFSET 0 0 1\n  CHANNELS 1 Zrotation\n".to_vec();
    let source = Generated::new(vec![
        (
            b"HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 1 Zrotation\n".to_vec(),
            1,
        ),
        (joint, 1_000_000),
    ]);
    let (result, largest) = largest_allocation(|| {
        BvhReader::new(BufReader::new(source), "deep.bvh", BvhConfig::cmu()).map(|_| ())
    });
    match result {
        Err(BvhError::Limit { what, limit, .. }) => {
            assert_eq!((what, limit), ("number of joints", 1024));
        }
        other => panic!("expected the joint cap, got {other:?}"),
    }
    // 1024 joints of ~100 bytes each: far below what a million would take (~100 MB).
    assert!(largest < 1 << 20, "largest allocation {largest} B");
}

#[test]
fn bvh_with_a_million_sibling_joints_is_refused_at_the_cap() {
    let joint = b" JOINT j\n {\n  OFFSET 0 0 1\n  CHANNELS 1 Zrotation\n }\n".to_vec();
    let source = Generated::new(vec![
        (b"HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n".to_vec(), 1),
        (joint, 1_000_000),
    ]);
    let (result, largest) = largest_allocation(|| {
        BvhReader::new(BufReader::new(source), "wide.bvh", BvhConfig::cmu()).map(|_| ())
    });
    assert!(
        matches!(result, Err(BvhError::Limit { limit: 1024, .. })),
        "{result:?}"
    );
    assert!(largest < 1 << 20, "largest allocation {largest} B");
}

#[test]
fn bvh_with_a_10_mb_line_is_refused() {
    // In the header (one endless OFFSET line) and in the motion.
    for (prefix, body) in [
        (b"HIERARCHY\nROOT Hips\n{\n OFFSET".to_vec(), b" 0".to_vec()),
        (
            format!("{ONE_JOINT_BVH}Frames: 1\nFrame Time: 0.01\n").into_bytes(),
            b"1 ".to_vec(),
        ),
    ] {
        let source = Generated::new(vec![(prefix, 1), (body, 5_000_000)]);
        let (result, largest) = largest_allocation(|| {
            let config = BvhConfig {
                names: taskstack::io::bvh::BvhNames::Custom(Vec::new()),
                ..BvhConfig::cmu()
            };
            BvhReader::new(BufReader::new(source), "long.bvh", config)
                .and_then(|r| r.collect::<Result<Vec<_>, _>>())
                .map(|_| ())
        });
        assert!(
            matches!(
                result,
                Err(BvhError::Limit {
                    what: "line length in bytes",
                    ..
                })
            ),
            "{result:?}"
        );
        assert!(largest < 4 << 20, "largest allocation {largest} B");
    }
}

#[test]
fn kinect_line_of_10_mb_is_refused_without_reading_it_whole() {
    let source = Generated::new(vec![(b"1,".to_vec(), 5_000_000)]);
    let (result, largest) = largest_allocation(|| {
        KinectReader::new(BufReader::new(source), "long.csv", KinectConfig::default())
            .collect::<Result<Vec<_>, _>>()
    });
    assert!(
        matches!(
            result,
            Err(KinectError::LineTooLong {
                line: 1,
                limit: 65536,
                ..
            })
        ),
        "{result:?}"
    );
    assert!(largest < 1 << 20, "largest allocation {largest} B");
}

// ---------------------------------------------------------------------------------------------
// Regressions: bugs the fuzzing found, each on the real file with one value replaced.

/// The real text with the first occurrence of `from` replaced by `to`.
fn replaced(text: &[u8], from: &str, to: &str) -> String {
    let text = String::from_utf8(text.to_vec()).expect("UTF-8");
    assert!(text.contains(from), "`{from}` not in the file");
    text.replacen(from, to, 1)
}

#[test]
fn dh_with_a_huge_com_is_refused_instead_of_giving_an_infinite_com() {
    // Found by `dh_survives_mutation`: `1e308` for a CoM coordinate loaded, and the whole-body
    // CoM was (inf, ...). Now every number is capped at MAX_MAGNITUDE = 1e6.
    let text = replaced(&inputs().dh[1], "com = [0.025419754666915", "com = [1e308");
    match Model::from_dh_str(&text, "lfoot.toml") {
        Err(e) => {
            assert_eq!(
                e.problem(),
                Some(&taskstack::model::dh::DhProblem::TooLarge(1e308))
            );
            assert!(e.to_string().contains("base, field `com`"), "{e}");
        }
        Ok(_) => panic!("1e308 accepted"),
    }
    // Just below the cap loads, and everything stays finite.
    let text = replaced(&inputs().dh[1], "com = [0.025419754666915", "com = [1e6");
    check_model(&Model::from_dh_str(&text, "lfoot.toml").expect("1e6 is allowed"));
}

#[test]
fn urdf_huge_numbers_negative_velocity_or_effort_and_nan_inertia_are_refused() {
    use taskstack::model::UrdfError;
    let urdf = &inputs().urdf;
    let load = |text: String| Model::from_urdf_str(&text, &UrdfOptions::default());
    let huge = load(replaced(
        urdf,
        "<mass value=\"0.07842\"/>",
        "<mass value=\"1e308\"/>",
    ));
    assert!(
        matches!(huge, Err(UrdfError::TooLarge { value: 1e308, .. })),
        "{huge:?}"
    );
    let negative = load(replaced(
        urdf,
        "velocity=\"8.26797\"",
        "velocity=\"-8.26797\"",
    ));
    assert!(
        matches!(negative, Err(UrdfError::NegativeVelocity { velocity: -8.26797, ref joint }) if joint == "HeadYaw"),
        "{negative:?}"
    );
    let effort = |from: &str, to: &str| load(replaced(urdf, from, to));
    let negative = effort("effort=\"1.547\"", "effort=\"-1.547\"");
    assert!(
        matches!(negative, Err(UrdfError::NegativeEffort { effort: -1.547, ref joint }) if joint == "HeadYaw"),
        "{negative:?}"
    );
    // A missing (urdf-rs: 0) effort is "not stated", read as no limit.
    let head = |model: Model| model.variables()[model.variable_index("HeadYaw").unwrap()].clone();
    let unstated = effort("effort=\"1.547\"", "effort=\"0\"");
    assert_eq!(head(unstated.unwrap()).effort, f64::INFINITY);
    assert_eq!(
        head(effort("effort=\"1.547\"", "effort=\"1.547\"").unwrap()).effort,
        1.547
    );
    let nan = load(replaced(urdf, "ixx=\"1.60324e-05\"", "ixx=\"nan\""));
    assert!(
        matches!(nan, Err(UrdfError::NonFinite { ref place, .. }) if place.ends_with("inertia")),
        "{nan:?}"
    );
}
