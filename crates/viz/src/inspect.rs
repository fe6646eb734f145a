//! Reading a recording back with rerun's own decoder: which stores, entities, timelines and how many rows, whether
//! its footer is there, and whether two recordings hold the same content.

use crate::error::VizError;
use rerun::StoreKind;
use rerun::external::re_log_encoding::DecoderApp;
use rerun::external::re_log_types::LogMsg;
use rerun::log::Chunk;
use std::collections::{BTreeMap, BTreeSet};
use std::io::BufReader;
use std::path::Path;

/// What an `.rrd` file holds.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RrdSummary {
    /// Recording ids of the recording stores.
    pub recordings: Vec<String>,
    /// Recording ids of the blueprint stores.
    pub blueprints: Vec<String>,
    /// Rows per entity path of the recording stores (static rows included).
    pub rows: BTreeMap<String, usize>,
    /// Static rows per entity path of the recording stores.
    pub static_rows: BTreeMap<String, usize>,
    /// Timelines used by the recording stores.
    pub timelines: BTreeSet<String>,
    /// Entity paths of the blueprint stores.
    pub blueprint_entities: BTreeSet<String>,
    /// Blueprint activation commands seen.
    pub activations: usize,
    /// Data chunks in the recording stores.
    pub chunks: usize,
    /// Recording ids of the stores (recordings and blueprints) that the file's RRD footer has a manifest for.
    pub footer_manifests: BTreeSet<String>,
}

impl RrdSummary {
    /// Rows logged at `entity` (e.g. `/robots/experia/scan`), 0 when absent.
    pub fn rows_at(&self, entity: &str) -> usize {
        self.rows.get(entity).copied().unwrap_or(0)
    }
}

/// Decodes every message of the `.rrd` file at `path`.
pub fn summarize(path: &Path) -> Result<RrdSummary, VizError> {
    let err = |cause: String| VizError::Read { path: path.to_path_buf(), cause };
    let mut s = RrdSummary::default();
    let mut messages = decoder(path)?;
    for msg in messages.by_ref() {
        match msg.map_err(|e| err(e.to_string()))? {
            LogMsg::SetStoreInfo(info) => {
                let id = info.info.store_id.recording_id().to_string();
                match info.info.store_id.kind() {
                    StoreKind::Recording => s.recordings.push(id),
                    StoreKind::Blueprint => s.blueprints.push(id),
                }
            }
            LogMsg::ArrowMsg(store, arrow) => {
                let chunk = Chunk::from_arrow_msg(&arrow).map_err(|e| err(e.to_string()))?;
                let entity = chunk.entity_path().to_string();
                match store.kind() {
                    StoreKind::Recording => {
                        s.chunks += 1;
                        *s.rows.entry(entity.clone()).or_default() += chunk.num_rows();
                        if chunk.is_static() {
                            *s.static_rows.entry(entity).or_default() += chunk.num_rows();
                        }
                        s.timelines.extend(chunk.timelines().keys().map(|t| t.to_string()));
                    }
                    StoreKind::Blueprint => {
                        s.blueprint_entities.insert(entity);
                    }
                }
            }
            LogMsg::BlueprintActivationCommand(_) => s.activations += 1,
        }
    }
    // The footer is read with the last message; a file without one has no manifests.
    let manifests = messages.rrd_manifests().map_err(|e| err(format!("its RRD footer: {e}")))?;
    s.footer_manifests = manifests.iter().map(|m| m.store_id.recording_id().to_string()).collect();
    Ok(s)
}

/// The first message in which the recordings at `a` and `b` differ (its index and what it is), or `None` when
/// they hold the same messages in the same order: same stores, chunks, row ids, times and data.
///
/// This is what "reproducible" means for a recording: the bytes of two files may differ in the footer, whose
/// per-store manifests rerun writes in hash-map order.
pub fn first_difference(a: &Path, b: &Path) -> Result<Option<String>, VizError> {
    let (mut xs, mut ys) = (decoder(a)?, decoder(b)?);
    for i in 0.. {
        let x = xs.next().transpose().map_err(|e| VizError::Read { path: a.to_path_buf(), cause: e.to_string() })?;
        let y = ys.next().transpose().map_err(|e| VizError::Read { path: b.to_path_buf(), cause: e.to_string() })?;
        match (x, y) {
            (None, None) => return Ok(None),
            (Some(x), None) => return Ok(Some(format!("message {i} ({}) is missing from the second", what(&x)))),
            (None, Some(y)) => return Ok(Some(format!("message {i} ({}) is missing from the first", what(&y)))),
            (Some(x), Some(y)) if x != y => {
                return Ok(Some(format!("message {i} differs: {} against {}", what(&x), what(&y))));
            }
            _ => {}
        }
    }
    unreachable!("the loop returns")
}

/// A short description of a message: its kind, and for data its store and entity.
fn what(msg: &LogMsg) -> String {
    match msg {
        LogMsg::SetStoreInfo(info) => format!("store info of {}", info.info.store_id.recording_id()),
        LogMsg::ArrowMsg(store, arrow) => match Chunk::from_arrow_msg(arrow) {
            Ok(chunk) => format!("a chunk of {} in {}", chunk.entity_path(), store.recording_id()),
            Err(_) => format!("an undecodable chunk in {}", store.recording_id()),
        },
        LogMsg::BlueprintActivationCommand(_) => "a blueprint activation".to_string(),
    }
}

type Messages = rerun::external::re_log_encoding::DecoderIterator<LogMsg, BufReader<std::fs::File>>;

/// rerun's decoder over the file at `path`.
fn decoder(path: &Path) -> Result<Messages, VizError> {
    let file =
        std::fs::File::open(path).map_err(|e| VizError::Read { path: path.to_path_buf(), cause: e.to_string() })?;
    Ok(DecoderApp::decode_lazy(BufReader::new(file)))
}
