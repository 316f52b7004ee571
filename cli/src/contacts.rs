//! `taskstack contacts`: the contact change events of a clip in a scene.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use taskstack::human::HumanFrame;
use taskstack::imitation::reference::contact_events::{
    ContactChange, ContactConfig, ContactThresholds, contact_events,
};
use taskstack::io::clip::Clip;
use taskstack::scene::Scene;

use crate::Report;

/// List when a clip's human starts and stops resting a hand or foot on a scene's surfaces.
///
/// The hands, the feet and (with --knees) the knees: the chronological contact change list of
/// Di Fava et al. (eq. 14–15), one offline pass with hysteresis.
///
/// The scene is a TOML file of horizontal rectangles (floor, table, stool) in the clip's world
/// frame (metres, z up); see the `taskstack::scene` docs. Times are the clip's, in seconds.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct ContactsArgs {
    /// The clip: a BVH file (CMU) or a Kinect v2 CSV.
    clip: PathBuf,
    /// The scene file (TOML).
    #[arg(long, value_name = "SCENE.toml")]
    scene: PathBuf,
    /// Also list the knees' contacts (a knee joint centre within 9 cm of a surface).
    #[arg(long)]
    knees: bool,
}

pub(crate) fn run(args: ContactsArgs, report: Report) -> Result<ExitCode> {
    let scene = Scene::from_toml_file(&args.scene)?;
    let clip = Clip::open(&args.clip).with_context(|| args.clip.display().to_string())?;
    let capture = clip.capture();
    let frames = clip
        .collect::<Result<Vec<HumanFrame>, _>>()
        .with_context(|| args.clip.display().to_string())?;
    let config = ContactConfig {
        knees: args.knees.then_some(ContactThresholds::KNEES),
        ..ContactConfig::for_capture(capture)
    };
    let events = contact_events(&frames, &scene, &config)?;
    let surface = |i: usize| scene.surfaces()[i].name();
    let change = |c: ContactChange| match c {
        ContactChange::Enter => "enter",
        ContactChange::Leave => "leave",
    };
    if report.json {
        let list: Vec<_> = events
            .iter()
            .map(|e| {
                json!({"time": e.time, "frame": e.frame, "link": e.link.name(),
                       "surface": surface(e.surface), "change": change(e.change)})
            })
            .collect();
        println!("{}", json!({ "events": list }));
    } else if !report.quiet {
        println!(
            "{:>8}  {:>5}  {:<10}  {:<12}  change",
            "time (s)", "frame", "link", "surface"
        );
        for e in &events {
            println!(
                "{:>8.3}  {:>5}  {:<10}  {:<12}  {}",
                e.time,
                e.frame,
                e.link.name(),
                surface(e.surface),
                change(e.change)
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
