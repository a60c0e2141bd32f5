//! `flexiso open [INPUT]`: the explorer window on a volume (by default the
//! built-in synthetic field). The window opens at once; the volume is read
//! and its tree built in the background.

use std::path::PathBuf;

use super::input::InputArgs;
use crate::app::{FlexisoApp, Request};

/// Arguments of `flexiso open`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// The volume.
    #[command(flatten)]
    pub input: InputArgs,
    /// Write one line per frame (time, frame ms, UI ms, job stage) here.
    #[arg(long, value_name = "TSV")]
    pub frame_log: Option<PathBuf>,
    /// Write the screen positions of the tree's arcs and markers here
    /// whenever they change (for scripted clicks, see scripts/screenshot.sh).
    #[arg(long, value_name = "FILE", hide = true)]
    pub ui_dump: Option<PathBuf>,
    /// Open this session (its volume and scene; see the README's
    /// Sessions) instead of INPUT.
    #[arg(long, value_name = "JSON")]
    pub session: Option<PathBuf>,
    /// Initial window size.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(f32, f32)>,
}

fn parse_size(s: &str) -> Result<(f32, f32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH (e.g. 1600x1000)"))?;
    let n = |t: &str| match t.trim().parse::<f32>() {
        Ok(v) if (200.0..=16384.0).contains(&v) => Ok(v),
        _ => Err(format!("'{t}' is not a size between 200 and 16384")),
    };
    Ok((n(w)?, n(h)?))
}

/// Runs `flexiso open`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Options that do not need the file are checked before any window.
    let mut source = args.input.source()?;
    let session = match &args.session {
        Some(p) => {
            let s = crate::session::Session::read(p)?;
            source = crate::field::source::VolumeSource::parse(
                &s.volume_input(p),
                crate::field::io::ReadOptions::default(),
            )?;
            Some(p.clone())
        }
        None => None,
    };
    let (w, h) = args.size.unwrap_or((1400.0, 900.0));
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("flexiso")
            .with_inner_size([w, h])
            .with_min_inner_size([640.0, 400.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    // The engine's rayon workers run below the UI thread's priority (see
    // yield_to_ui); a pool already built (never, from main) stays as it is.
    let _ = rayon::ThreadPoolBuilder::new()
        .start_handler(|_| crate::app::yield_to_ui())
        .build_global();
    let frame_log = args.frame_log.clone();
    let ui_dump = args.ui_dump.clone();
    eframe::run_native(
        "flexiso",
        options,
        Box::new(move |cc| {
            let mut app = FlexisoApp::new(cc, Request::Open(source));
            if let Some(p) = &frame_log {
                app.set_frame_log(p)?;
            }
            if let Some(p) = ui_dump {
                app.set_ui_dump(p);
            }
            if let Some(p) = &session {
                app.open_session(p);
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the window: {e}"))
}
