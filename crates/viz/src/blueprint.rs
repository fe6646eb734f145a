//! The layout a recording opens with: a rerun blueprint, built with fixed ids so that it is reproducible.
//!
//! rerun's Rust blueprint API (`rerun::blueprint`) gives every container and view a random UUID and every row a
//! wall-clock id; the same layout is written here from the blueprint archetypes directly, with ids that depend on
//! the layout only. The blueprint travels inside the recording (a separate blueprint store, made the default
//! for the `mrslam` application), so `rerun run.rrd` opens laid out.

use crate::recorder::{APP_ID, Recorder};
use rerun::blueprint::components::{
    AutoLayout, AutoViews, ColumnShare, ContainerKind, IncludedContent, QueryExpression, RootContainer, RowShare,
    TimelineName, ViewClass,
};
use rerun::components::Name;
use rerun::datatypes::{Bool, Float32, Uuid};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    ContainerBlueprint, TimePanelBlueprint, ViewBlueprint, ViewContents, ViewportBlueprint,
};
use rerun::{ApplicationId, AsComponents, EntityPath, StoreId, StoreKind, TimeCell, TimePoint};

/// A kind of view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewKind {
    /// A 2D spatial view.
    Spatial2D,
    /// Scalars against time.
    TimeSeries,
    /// Text events.
    TextLog,
}

impl ViewKind {
    fn class(self) -> &'static str {
        match self {
            ViewKind::Spatial2D => "2D",
            ViewKind::TimeSeries => "TimeSeries",
            ViewKind::TextLog => "TextLog",
        }
    }
}

/// A layout: containers of views.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// Side by side, with relative widths (empty: equal).
    Horizontal(Vec<Layout>, Vec<f32>),
    /// One above the other, with relative heights (empty: equal).
    Vertical(Vec<Layout>, Vec<f32>),
    /// One at a time, as tabs.
    Tabs(Vec<Layout>),
    /// A view.
    View {
        /// Kind.
        kind: ViewKind,
        /// Title.
        name: String,
        /// The entity whose frame the view shows (`/` for the world).
        origin: EntityPath,
        /// Query expressions, e.g. `+ /robots/**`, `- /robots/prawn/scan`.
        contents: Vec<String>,
    },
}

impl Layout {
    /// A view of `kind` called `name`, at `origin`, showing `contents`.
    pub fn view(kind: ViewKind, name: &str, origin: EntityPath, contents: &[String]) -> Layout {
        Layout::View { kind, name: name.to_string(), origin, contents: contents.to_vec() }
    }

    /// Every view's name, depth first.
    pub fn view_names(&self) -> Vec<String> {
        match self {
            Layout::Horizontal(items, _) | Layout::Vertical(items, _) | Layout::Tabs(items) => {
                items.iter().flat_map(Layout::view_names).collect()
            }
            Layout::View { name, .. } => vec![name.clone()],
        }
    }
}

/// A query expression: `prefix` (`+` or `-`) and `p`, with all its descendants when `deep`.
pub fn query(prefix: char, p: &EntityPath, deep: bool) -> String {
    if deep { format!("{prefix} {p}/**") } else { format!("{prefix} {p}") }
}

type Row = (rerun::log::RowId, TimePoint, Vec<rerun::SerializedComponentBatch>);

/// Builds the blueprint store's rows for a layout.
struct Builder<'r> {
    rec: &'r mut Recorder,
    next_uuid: u64,
    time: TimePoint,
    rows: Vec<(EntityPath, Vec<Row>)>,
}

/// A fixed, valid (version 4, variant 1) UUID per layout node.
fn uuid(n: u64) -> Uuid {
    let mut bytes = [0u8; 16];
    bytes[..8].copy_from_slice(b"mrslamvz");
    bytes[8..].copy_from_slice(&n.to_be_bytes());
    bytes[6] = (bytes[6] & 0x0f) | 0x40;
    bytes[8] = (bytes[8] & 0x3f) | 0x80;
    Uuid { bytes }
}

/// `8-4-4-4-12` lower-case hex, as rerun writes UUIDs in blueprint paths.
fn hyphenated(u: &Uuid) -> String {
    let h: String = u.bytes.iter().map(|b| format!("{b:02x}")).collect();
    format!("{}-{}-{}-{}-{}", &h[0..8], &h[8..12], &h[12..16], &h[16..20], &h[20..32])
}

impl Builder<'_> {
    fn push(&mut self, entity: EntityPath, data: &dyn AsComponents) {
        let row = (self.rec.ids().row(), self.time.clone(), data.as_serialized_batches());
        self.rows.push((entity, vec![row]));
    }

    /// Writes a node and its children; returns its blueprint path and UUID.
    fn node(&mut self, layout: &Layout) -> (String, Uuid) {
        self.next_uuid += 1;
        let id = uuid(self.next_uuid);
        match layout {
            Layout::View { kind, name, origin, contents } => {
                let path = format!("view/{}", hyphenated(&id));
                let query = ViewContents::new(contents.iter().map(|q| QueryExpression(q.as_str().into())));
                self.push(EntityPath::from(format!("{path}/ViewContents")), &query);
                let view = ViewBlueprint::new(ViewClass(kind.class().into()))
                    .with_display_name(Name(name.as_str().into()))
                    .with_space_origin(origin.to_string());
                self.push(EntityPath::from(path.as_str()), &view);
                (path, id)
            }
            Layout::Horizontal(items, shares) => self.container(id, ContainerKind::Horizontal, items, shares),
            Layout::Vertical(items, shares) => self.container(id, ContainerKind::Vertical, items, shares),
            Layout::Tabs(items) => self.container(id, ContainerKind::Tabs, items, &[]),
        }
    }

    fn container(&mut self, id: Uuid, kind: ContainerKind, items: &[Layout], shares: &[f32]) -> (String, Uuid) {
        let children: Vec<String> = items.iter().map(|c| self.node(c).0).collect();
        let path = format!("container/{}", hyphenated(&id));
        let mut arch =
            ContainerBlueprint::new(kind).with_contents(children.iter().map(|c| IncludedContent(c.as_str().into())));
        if !shares.is_empty() && shares.len() == items.len() {
            arch = match kind {
                ContainerKind::Horizontal => arch.with_col_shares(shares.iter().map(|s| ColumnShare(Float32(*s)))),
                _ => arch.with_row_shares(shares.iter().map(|s| RowShare(Float32(*s)))),
            };
        }
        self.push(EntityPath::from(path.as_str()), &arch);
        (path, id)
    }
}

impl Recorder {
    /// Sends `layout` as the recording's default blueprint, with the time panel on `sim_time`.
    pub fn send_layout(&mut self, layout: &Layout) {
        let blueprint_id = format!("{}-blueprint", self.store_id().recording_id());
        let store = StoreId::new(StoreKind::Blueprint, ApplicationId::from(APP_ID), blueprint_id);
        let mut b = Builder {
            rec: self,
            next_uuid: 0,
            time: TimePoint::default().with_index("blueprint", TimeCell::from_sequence(0)),
            rows: Vec::new(),
        };
        // Wrap a lone view so that the root is a container, as rerun's own API does.
        let root = match layout {
            Layout::View { .. } => Layout::Tabs(vec![layout.clone()]),
            other => other.clone(),
        };
        let (_, root_id) = b.node(&root);
        let viewport = ViewportBlueprint::new()
            .with_root_container(RootContainer(root_id))
            .with_auto_layout(AutoLayout(Bool(false)))
            .with_auto_views(AutoViews(Bool(false)));
        b.push(EntityPath::from("viewport"), &viewport);
        let panel = TimePanelBlueprint::new().with_timeline(TimelineName(crate::recorder::SIM_TIME.into()));
        b.push(EntityPath::from("time_panel"), &panel);
        let rows = std::mem::take(&mut b.rows);
        self.send_blueprint(store, rows);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uuids_are_fixed_and_well_formed() {
        let s = hyphenated(&uuid(1));
        assert_eq!(s, hyphenated(&uuid(1)));
        assert_ne!(s, hyphenated(&uuid(2)));
        assert_eq!(s.len(), 36);
        assert_eq!(&s[14..15], "4", "version 4: {s}");
        assert!(matches!(&s[19..20], "8" | "9" | "a" | "b"), "variant 1: {s}");
    }

    #[test]
    fn view_names_depth_first() {
        let v = |n: &str| Layout::view(ViewKind::TextLog, n, EntityPath::from("events"), &["+ /**".into()]);
        let l = Layout::Vertical(vec![v("a"), Layout::Horizontal(vec![v("b"), v("c")], vec![])], vec![1.0, 2.0]);
        assert_eq!(l.view_names(), ["a", "b", "c"]);
    }
}
