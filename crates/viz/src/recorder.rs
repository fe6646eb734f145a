//! The recording itself: a rerun store written to one or more destinations, reproducibly.
//!
//! rerun's own `RecordingStream` stamps every row and chunk with wall-clock ids, adds a `log_time` timeline and
//! cuts chunks on a wall-clock timer, so two runs of one scenario would give different files. The recorder
//! therefore builds the chunks itself: row and chunk ids come from counters, the only timelines are `sim_time`
//! and `step`, and rows are grouped into chunks per entity every [`Recorder::FLUSH_PERIOD_S`] of simulated
//! time (or sooner when a lot is pending). The chunks go straight to rerun's sinks (file or gRPC), which encode
//! them unchanged: same scenario, same seed, same build ⇒ the same messages (the `.rrd` footer that the file sink
//! adds at the end lists them per store in hash-map order, so the bytes may differ there; see
//! [`crate::inspect::first_difference`]).

use crate::error::VizError;
use crate::target::Target;
use rerun::external::arrow::array::Array;
use rerun::external::re_log_types::{BlueprintActivationCommand, LogMsg, SetStoreInfo, StoreInfo, StoreSource};
use rerun::log::{Chunk, ChunkId, RowId};
use rerun::sink::LogSink;
use rerun::{
    ApplicationId, AsComponents, EntityPath, SerializedComponentBatch, StoreId, StoreKind, TimeCell, TimePoint,
};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

/// The application id of every mrslam recording (the viewer groups recordings and blueprints by it).
pub const APP_ID: &str = "mrslam";
/// Name of the simulated-time timeline (a duration, seconds).
pub const SIM_TIME: &str = "sim_time";
/// Name of the simulation-step timeline (a sequence).
pub const STEP: &str = "step";

/// Time part of every id: 2024-01-01T00:00:00Z. Ids only need to be unique and ordered, not wall-clock.
const ID_EPOCH_NS: u128 = 1_704_067_200_000_000_000;

/// Deterministic row and chunk ids, in logging order.
#[derive(Debug, Default)]
pub(crate) struct Ids {
    rows: u64,
    chunks: u64,
}

impl Ids {
    /// The next row id.
    pub(crate) fn row(&mut self) -> RowId {
        self.rows += 1;
        RowId::from_u128((ID_EPOCH_NS << 64) | self.rows as u128)
    }
    /// The next chunk id.
    pub(crate) fn chunk(&mut self) -> ChunkId {
        self.chunks += 1;
        ChunkId::from_u128((ID_EPOCH_NS << 64) | self.chunks as u128)
    }
}

type Row = (RowId, TimePoint, Vec<SerializedComponentBatch>);

/// Counts of what a recording holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RecordingStats {
    /// Rows logged (one per log call).
    pub rows: u64,
    /// Chunks sent.
    pub chunks: u64,
}

/// A rerun recording being written: the store, its destinations, the current time and the pending rows.
pub struct Recorder {
    store: StoreId,
    sinks: Vec<(String, Box<dyn LogSink>)>,
    ids: Ids,
    time: TimePoint,
    sim_time: f64,
    step: u64,
    next_flush: f64,
    pending: BTreeMap<EntityPath, Vec<Row>>,
    pending_bytes: usize,
    stats: RecordingStats,
    error: Option<VizError>,
    /// Files being written under a partial name, and their names once finished.
    renames: Vec<(PathBuf, PathBuf)>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let targets: Vec<&str> = self.sinks.iter().map(|(t, _)| t.as_str()).collect();
        f.debug_struct("Recorder").field("store", &self.store).field("targets", &targets).finish_non_exhaustive()
    }
}

impl Recorder {
    /// Rows are grouped into one chunk per entity over this much simulated time.
    pub const FLUSH_PERIOD_S: f64 = 2.0;
    /// Pending rows are sent early when they exceed this many bytes.
    const FLUSH_BYTES: usize = 16 << 20;

    /// Opens every target (creating files, starting or dialling viewers) and starts the recording `recording_id`
    /// (fixed, e.g. derived from the scenario name and seed), named `name` in the viewer.
    ///
    /// Fails before anything is recorded when a target cannot be opened.
    pub fn open(targets: &[Target], recording_id: &str, name: &str) -> Result<Recorder, VizError> {
        let mut sinks = Vec::with_capacity(targets.len());
        let mut renames = Vec::new();
        for t in targets {
            sinks.push((t.describe(), t.open()?));
            if let Target::File(path) = t {
                renames.push((crate::target::partial_path(path), path.clone()));
            }
        }
        let store = StoreId::new(StoreKind::Recording, ApplicationId::from(APP_ID), recording_id);
        let mut rec = Recorder {
            store: store.clone(),
            sinks,
            ids: Ids::default(),
            time: TimePoint::STATIC,
            sim_time: 0.0,
            step: 0,
            next_flush: Self::FLUSH_PERIOD_S,
            pending: BTreeMap::new(),
            pending_bytes: 0,
            stats: RecordingStats::default(),
            error: None,
            renames,
        };
        let info = SetStoreInfo { row_id: *rec.ids.row(), info: store_info(store) };
        rec.send(LogMsg::SetStoreInfo(info));
        // The recording's name in the viewer; no start time, so that the file does not depend on the clock.
        rec.log_static(&EntityPath::properties(), &rerun::RecordingInfo::new().with_name(name));
        rec.set_time(0, 0.0);
        Ok(rec)
    }

    /// The store this recording writes.
    pub fn store_id(&self) -> &StoreId {
        &self.store
    }

    /// Sets the time of the following log calls: simulation step and simulated seconds.
    pub fn set_time(&mut self, step: u64, sim_time: f64) {
        self.sim_time = sim_time;
        self.step = step;
        self.time = TimePoint::default()
            .with_index(STEP, TimeCell::from_sequence(step.min(i64::MAX as u64) as i64))
            .with_index(SIM_TIME, TimeCell::from_duration_nanos((sim_time * 1e9).round() as i64));
        if sim_time >= self.next_flush {
            self.flush();
            while self.next_flush <= sim_time {
                self.next_flush += Self::FLUSH_PERIOD_S;
            }
        }
    }

    /// Simulated time of the following log calls, seconds.
    pub fn sim_time(&self) -> f64 {
        self.sim_time
    }

    /// Simulation step of the following log calls.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Logs `data` at `entity` at the current time.
    pub fn log(&mut self, entity: &EntityPath, data: &dyn AsComponents) {
        self.log_all(entity, &[data]);
    }

    /// Logs several archetypes at `entity` as one row at the current time (e.g. an image and its placement).
    pub fn log_all(&mut self, entity: &EntityPath, data: &[&dyn AsComponents]) {
        let batches: Vec<SerializedComponentBatch> = data.iter().flat_map(|d| d.as_serialized_batches()).collect();
        if batches.is_empty() {
            return;
        }
        self.pending_bytes += batches.iter().map(|b| b.array.get_array_memory_size()).sum::<usize>();
        let row = (self.ids.row(), self.time.clone(), batches);
        self.pending.entry(entity.clone()).or_default().push(row);
        self.stats.rows += 1;
        if self.pending_bytes >= Self::FLUSH_BYTES {
            self.flush();
        }
    }

    /// Logs `data` at `entity` as static (valid at all times); sent at once.
    pub fn log_static(&mut self, entity: &EntityPath, data: &dyn AsComponents) {
        self.log_static_all(entity, &[data]);
    }

    /// Logs several archetypes at `entity` as one static row; sent at once.
    pub fn log_static_all(&mut self, entity: &EntityPath, data: &[&dyn AsComponents]) {
        let batches: Vec<SerializedComponentBatch> = data.iter().flat_map(|d| d.as_serialized_batches()).collect();
        if batches.is_empty() {
            return;
        }
        let row = (self.ids.row(), TimePoint::STATIC, batches);
        self.stats.rows += 1;
        self.send_rows(entity.clone(), vec![row]);
    }

    /// Sends a blueprint (messages of a blueprint store, see [`crate::blueprint`]) and makes it the default.
    pub(crate) fn send_blueprint(&mut self, store: StoreId, chunks: Vec<(EntityPath, Vec<Row>)>) {
        let row_id = *self.ids.row();
        self.send(LogMsg::SetStoreInfo(SetStoreInfo { row_id, info: store_info(store.clone()) }));
        for (entity, rows) in chunks {
            self.send_chunk(&store, entity, rows);
        }
        let cmd = BlueprintActivationCommand { blueprint_id: store, make_active: true, make_default: true };
        self.send(LogMsg::BlueprintActivationCommand(cmd));
    }

    /// The id generator, for blueprint rows.
    pub(crate) fn ids(&mut self) -> &mut Ids {
        &mut self.ids
    }

    /// Sends every pending row, one chunk per entity, in entity order.
    pub fn flush(&mut self) {
        let pending = std::mem::take(&mut self.pending);
        self.pending_bytes = 0;
        for (entity, rows) in pending {
            self.send_rows(entity, rows);
        }
    }

    /// Flushes, waits for every destination to take the data, and closes the recording (an `.rrd` file gets its
    /// footer). Reports the first error met while recording.
    pub fn finish(mut self) -> Result<RecordingStats, VizError> {
        self.flush();
        for (target, sink) in &self.sinks {
            if let Err(e) = sink.flush_blocking(Duration::from_secs(30))
                && self.error.is_none()
            {
                self.error = Some(VizError::Flush { target: target.clone(), cause: e.to_string() });
            }
        }
        let stats = self.stats;
        let mut error = self.error.take();
        self.sinks.clear(); // dropping a file sink writes the footer and closes the file
        if error.is_none() {
            for (partial, path) in std::mem::take(&mut self.renames) {
                if let Err(e) = std::fs::rename(&partial, &path) {
                    error = Some(VizError::CreateFile { path, cause: format!("renaming {}: {e}", partial.display()) });
                    break;
                }
            }
        }
        match error {
            Some(e) => Err(e),
            None => Ok(stats),
        }
    }

    fn send_rows(&mut self, entity: EntityPath, rows: Vec<Row>) {
        let store = self.store.clone();
        self.send_chunk(&store, entity, rows);
    }

    fn send_chunk(&mut self, store: &StoreId, entity: EntityPath, rows: Vec<Row>) {
        let mut builder = Chunk::builder_with_id(self.ids.chunk(), entity.clone());
        for (row_id, time, batches) in rows {
            builder = builder.with_serialized_batches(row_id, time, batches);
        }
        let msg = builder.build().and_then(|chunk| chunk.to_arrow_msg());
        match msg {
            Ok(msg) => {
                self.stats.chunks += 1;
                self.send(LogMsg::ArrowMsg(store.clone(), msg));
            }
            Err(e) => {
                if self.error.is_none() {
                    self.error = Some(VizError::Encode { entity: entity.to_string(), cause: e.to_string() });
                }
            }
        }
    }

    fn send(&self, msg: LogMsg) {
        if let [(_, only)] = self.sinks.as_slice() {
            only.send(msg);
        } else {
            for (_, sink) in &self.sinks {
                sink.send(msg.clone());
            }
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        // A run that stopped early still leaves a readable recording of what happened up to there, under its
        // partial name (see `Target::File`).
        self.flush();
    }
}

fn store_info(store: StoreId) -> StoreInfo {
    StoreInfo::new(store, StoreSource::Other("mrslam".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_gets_its_name_only_when_finished() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.rrd");
        let partial = dir.path().join("run.partial.rrd");
        let rec = Recorder::open(&[Target::File(path.clone())], "test", "test").unwrap();
        drop(rec); // interrupted
        assert!(!path.exists(), "an interrupted recording must not look complete");
        assert!(partial.metadata().unwrap().len() > 0, "the partial recording is kept");
        let rec = Recorder::open(&[Target::File(path.clone())], "test", "test").unwrap();
        rec.finish().unwrap();
        assert!(path.metadata().unwrap().len() > 0);
        assert!(!partial.exists());
    }

    #[test]
    fn ids_are_unique_and_increasing() {
        let mut ids = Ids::default();
        let (a, b) = (ids.row(), ids.row());
        assert!(a < b);
        let (c, d) = (ids.chunk(), ids.chunk());
        assert!(c < d);
        let mut again = Ids::default();
        assert_eq!(again.row(), a, "ids depend on the logging order only");
    }
}
