//! Metrics as time series and events as text.

use crate::convert::{Rgba, color};
use crate::paths;
use crate::recorder::Recorder;
use rerun::components::TextLogLevel;
use rerun::{EntityPath, Scalars, SeriesLines, TextLog};

/// How bad an event is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Routine (resampling, a robot finished its route).
    Info,
    /// Worth a look (a collision, a rejected merge).
    Warn,
    /// Something failed.
    Error,
}

impl Recorder {
    /// Names and colours one time series (static), so that the plot's legend reads `name`.
    pub fn log_series_style(&mut self, entity: &EntityPath, name: &str, c: Rgba) {
        self.log_static(entity, &SeriesLines::new().with_names([name]).with_colors([color(c)]).with_widths([1.5]));
    }

    /// Logs one value of a time series at the current time (non-finite values are skipped).
    pub fn log_scalar(&mut self, entity: &EntityPath, value: f64) {
        if value.is_finite() {
            self.log(entity, &Scalars::single(value));
        }
    }

    /// Logs an event as a line of text at `events`, at the current time.
    pub fn log_event(&mut self, level: Level, text: &str) {
        self.log_text(&paths::events(), level, text);
    }

    /// Logs a line of text at `entity` (a text log of its own, e.g. `team/events`), at the current time.
    pub fn log_text(&mut self, entity: &EntityPath, level: Level, text: &str) {
        let level = match level {
            Level::Info => TextLogLevel::INFO,
            Level::Warn => TextLogLevel::WARN,
            Level::Error => TextLogLevel::ERROR,
        };
        self.log(entity, &TextLog::new(text).with_level(level));
    }
}
