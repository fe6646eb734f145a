//! Reading a recording back with rerun's own decoder: which stores, entities, timelines and how many rows.

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
    let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
    let mut s = RrdSummary::default();
    for msg in DecoderApp::decode_lazy(BufReader::new(file)) {
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
    Ok(s)
}
