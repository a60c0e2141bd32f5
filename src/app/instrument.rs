//! Instrumentation for scripts and measurements: the frame log (`flexiso
//! open --frame-log FILE`) and the dump of screen positions that scripted
//! clicks read (`--ui-dump FILE`, see scripts/screenshot.sh).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One line per frame: seconds since start, ms since the previous frame,
/// ms spent in the UI code, the job stage.
pub struct FrameLog {
    file: std::io::BufWriter<std::fs::File>,
    start: Instant,
    last: Option<Instant>,
}

impl FrameLog {
    /// A log written to `path` (created or truncated).
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        writeln!(file, "t_s\tframe_ms\tui_ms\tstage")?;
        Ok(Self {
            file,
            start: Instant::now(),
            last: None,
        })
    }

    /// Writes the line of the frame that just ended.
    pub fn frame(&mut self, ui_ms: f64, stage: &str) {
        let now = Instant::now();
        let frame_ms = self
            .last
            .map(|l| (now - l).as_secs_f64() * 1e3)
            .unwrap_or(0.0);
        self.last = Some(now);
        // A full disk only loses the log, never the window.
        let _ = writeln!(
            self.file,
            "{:.3}\t{frame_ms:.2}\t{ui_ms:.2}\t{stage}",
            (now - self.start).as_secs_f64(),
        );
        let _ = self.file.flush();
    }
}

/// The screen positions of the tree's arcs and markers and of the panels,
/// rewritten whenever they change.
pub struct UiDump {
    path: PathBuf,
    last: String,
    now: String,
}

impl UiDump {
    /// A dump written to `path`.
    pub fn new(path: PathBuf) -> Self {
        Self {
            path,
            last: String::new(),
            now: String::new(),
        }
    }

    /// A line `NAME X0 Y0 X1 Y1`.
    pub fn rect(&mut self, name: &str, r: egui::Rect) {
        self.now.push_str(&format!(
            "{name} {:.0} {:.0} {:.0} {:.0}\n",
            r.min.x, r.min.y, r.max.x, r.max.y
        ));
    }

    /// Any other line.
    pub fn line(&mut self, line: std::fmt::Arguments<'_>) {
        self.now.push_str(&line.to_string());
        self.now.push('\n');
    }

    /// Writes the frame's lines if they changed.
    pub fn flush(&mut self) {
        if self.now != self.last {
            // A script that reads it will say when it is missing.
            let _ = std::fs::write(&self.path, &self.now);
            self.last = std::mem::take(&mut self.now);
        } else {
            self.now.clear();
        }
    }
}
