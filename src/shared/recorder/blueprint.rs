//! The viewer layout sent with every recording (a Rerun blueprint).
//!
//! Rerun's Rust `blueprint` API builds containers and views but cannot set a 3D view's eye or a
//! 2D view's bounds; this module writes the same blueprint archetypes itself, so the one view of
//! the world is framed on the deformables and not on the largest collider.
//!
//! Layout (`docs/ARCHITECTURE.md` §8.5): the world view (3D or 2D) with the colour legend under
//! it on the left, and on the right three groups of time series — energy, quality, cost —
//! from [`PLOTS`]. With one deformable each plot shows several metrics of it; with several,
//! each metric gets a plot of its own with one series per body.

use rerun::external::re_log_types::{BlueprintActivationCommand, RecordingId};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    ContainerBlueprint, PanelBlueprint, TimePanelBlueprint, ViewBlueprint, ViewContents,
    ViewportBlueprint,
};
use rerun::external::re_sdk_types::blueprint::components::{
    AutoLayout, AutoViews, ContainerKind, PanelState, QueryExpression, RootContainer, ViewClass,
};
use rerun::{RecordingStream, RecordingStreamBuilder, RecordingStreamResult};

use super::super::math::{Vector, DIM};

/// A plot: its title and the metrics it shows.
pub type Plot = (&'static str, &'static [&'static str]);

/// Every `stats/<name>/<metric>` series the recorder logs, grouped as the layout shows them:
/// `(group, [(plot title, [metrics])])`.
pub const PLOTS: &[(&str, &[Plot])] = &[
    (
        "energy",
        &[(
            "energy (J)",
            &[
                "kinetic_energy",
                "elastic_energy",
                "gravity_energy",
                "total_energy",
            ],
        )],
    ),
    (
        "quality",
        &[
            ("smallest volume ratio", &["min_volume_ratio"]),
            ("deepest penetration (m)", &["max_penetration"]),
            (
                "inverted cells, contacts, frozen",
                &["inverted_elements", "contacts", "frozen"],
            ),
        ],
    ),
    (
        "cost",
        &[
            (
                "ms per step",
                &["ms_forces", "ms_contacts", "ms_integrate", "log_ms"],
            ),
            ("substeps", &["substeps"]),
        ],
    ),
];

/// Where the world view looks: the box it frames and, in 3D, the entity it follows.
#[derive(Clone, Debug, PartialEq)]
pub struct Framing {
    /// Lower corner of the box to frame.
    pub lo: Vector,
    /// Upper corner.
    pub hi: Vector,
    /// An entity the eye follows (3D), e.g. the one deformable's surface.
    pub track: Option<String>,
}

/// One node of the layout tree.
enum Node {
    View {
        class: &'static str,
        name: String,
        origin: String,
        contents: Vec<String>,
        framing: Option<Framing>,
    },
    Container {
        kind: ContainerKind,
        name: Option<String>,
        shares: Vec<f32>,
        children: Vec<Node>,
    },
}

fn view(class: &'static str, name: &str, origin: &str, contents: Vec<String>) -> Node {
    Node::View {
        class,
        name: name.to_string(),
        origin: origin.to_string(),
        contents,
        framing: None,
    }
}

fn container(kind: ContainerKind, name: Option<&str>, shares: &[f32], children: Vec<Node>) -> Node {
    Node::Container {
        kind,
        name: name.map(str::to_string),
        shares: shares.to_vec(),
        children,
    }
}

/// The plots of one group: for one body, each plot of [`PLOTS`] as it is; for several, one plot
/// per metric with a series per body.
fn group(name: &str, plots: &[Plot], bodies: &[String]) -> Node {
    let series = |metric: &str| -> Vec<String> {
        bodies
            .iter()
            .map(|b| format!("+ /stats/{b}/{metric}"))
            .collect()
    };
    let mut views = Vec::new();
    for (title, metrics) in plots {
        if bodies.len() == 1 {
            let contents = metrics.iter().flat_map(|m| series(m)).collect();
            views.push(view("TimeSeries", title, "/stats", contents));
        } else {
            for m in metrics.iter() {
                views.push(view("TimeSeries", m, "/stats", series(m)));
            }
        }
    }
    if views.len() == 1 {
        return views.pop().expect("one view");
    }
    container(ContainerKind::Tabs, Some(name), &[], views)
}

/// The gas plots of the bodies `gas` (those with chambers): each chamber's gauge pressure and
/// its volume, one plot each, a series per chamber and body.
fn gas_group(gas: &[String]) -> Node {
    let plot = |title: &str, quantity: &str| {
        let contents = gas
            .iter()
            .map(|b| format!("+ /stats/{b}/{quantity}/**"))
            .collect();
        view("TimeSeries", title, "/stats", contents)
    };
    container(
        ContainerKind::Tabs,
        Some("gas"),
        &[],
        vec![
            plot("gas pressure (Pa)", "gas_pressure"),
            plot("gas volume", "gas_volume"),
        ],
    )
}

/// The layout for these deformables (their entity names; `gas` those with gas chambers), with
/// a world view of `class` ("3D" or "2D") framed by `framing`.
fn layout(class: &'static str, (bodies, gas): (&[String], &[String]), framing: Framing) -> Node {
    let world = Node::View {
        class,
        name: "world".to_string(),
        origin: super::render::VIEW_ORIGIN.to_string(),
        contents: vec!["+ /world/**".to_string()],
        framing: Some(framing),
    };
    let legend = view(
        "TextDocument",
        "colours",
        "/legend",
        vec!["+ $origin".to_string()],
    );
    let left = container(
        ContainerKind::Vertical,
        None,
        &[6.0, 1.0],
        vec![world, legend],
    );
    let mut groups: Vec<Node> = PLOTS
        .iter()
        .map(|(name, plots)| group(name, plots, bodies))
        .collect();
    if !gas.is_empty() {
        groups.push(gas_group(gas));
    }
    let shares = vec![1.0; groups.len()];
    let right = container(ContainerKind::Vertical, None, &shares, groups);
    container(
        ContainerKind::Horizontal,
        None,
        &[3.0, 2.0],
        vec![left, right],
    )
}

/// Ids of the layout's nodes: deterministic within one blueprint (the blueprint's own store id
/// is random), formatted as UUIDs.
struct Ids(u64);

impl Ids {
    fn next(&mut self) -> [u8; 16] {
        self.0 += 1;
        let mut b = [0u8; 16];
        b[..6].copy_from_slice(b"sinew\0");
        b[8..].copy_from_slice(&self.0.to_be_bytes());
        b[6] = 0x40 | (b[6] & 0x0f); // version 4
        b[8] = 0x80 | (b[8] & 0x3f); // RFC 4122 variant
        b
    }
}

fn uuid_text(b: &[u8; 16]) -> String {
    let hex: String = b.iter().map(|x| format!("{x:02x}")).collect();
    format!(
        "{}-{}-{}-{}-{}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

/// Logs a node (children first) and returns its id and blueprint path.
fn log_node(
    rec: &RecordingStream,
    node: &Node,
    ids: &mut Ids,
) -> RecordingStreamResult<([u8; 16], String)> {
    let bytes = ids.next();
    let id = uuid_text(&bytes);
    match node {
        Node::View {
            class,
            name,
            origin,
            contents,
            framing,
        } => {
            let path = format!("view/{id}");
            rec.log(
                format!("{path}/ViewContents"),
                &ViewContents::new(contents.iter().map(|q| QueryExpression(q.as_str().into()))),
            )?;
            rec.log(
                path.as_str(),
                &ViewBlueprint::new(ViewClass((*class).into()))
                    .with_display_name(name.as_str())
                    .with_space_origin(origin.as_str()),
            )?;
            if let Some(f) = framing {
                super::render::frame_view(rec, &path, f.lo, f.hi, f.track.as_deref())?;
            }
            Ok((bytes, path))
        }
        Node::Container {
            kind,
            name,
            shares,
            children,
        } => {
            let path = format!("container/{id}");
            let mut children_paths = Vec::with_capacity(children.len());
            for child in children {
                children_paths.push(log_node(rec, child, ids)?.1);
            }
            let mut arch = ContainerBlueprint::new(*kind).with_contents(children_paths.clone());
            if let Some(name) = name {
                arch = arch.with_display_name(name.as_str());
            }
            match kind {
                ContainerKind::Horizontal => arch = arch.with_col_shares(shares.iter().copied()),
                ContainerKind::Vertical => arch = arch.with_row_shares(shares.iter().copied()),
                _ => {}
            }
            if *kind == ContainerKind::Tabs {
                if let Some(first) = children_paths.first() {
                    arch = arch.with_active_tab(first.as_str());
                }
            }
            rec.log(path.as_str(), &arch)?;
            Ok((bytes, path))
        }
    }
}

/// Sends sinew's layout for these deformables (their entity names; `gas` those with gas
/// chambers) to `target`, active and the application's default. `class` is the world view's
/// class ("3D" or "2D").
pub fn send(
    target: &RecordingStream,
    class: &'static str,
    (bodies, gas): (&[String], &[String]),
    framing: Framing,
) -> RecordingStreamResult<()> {
    let application = target
        .store_info()
        .map(|info| info.application_id().clone())
        .unwrap_or_else(|| "sinew".into());
    let (rec, storage) = RecordingStreamBuilder::new(application)
        .recording_id(RecordingId::random())
        .blueprint()
        .memory()?;
    rec.set_time_sequence("blueprint", 0);
    let mut ids = Ids(0);
    let (root, _) = log_node(&rec, &layout(class, (bodies, gas), framing), &mut ids)?;
    rec.log(
        "viewport",
        &ViewportBlueprint::new()
            .with_root_container(RootContainer(root.into()))
            .with_auto_layout(AutoLayout(false.into()))
            .with_auto_views(AutoViews(false.into())),
    )?;
    let collapsed = PanelBlueprint::new().with_state(PanelState::Collapsed);
    rec.log("blueprint_panel", &collapsed)?;
    rec.log("selection_panel", &collapsed)?;
    // Play back in simulated time (1 s of run per s), not one step per frame of the viewer.
    rec.log(
        "time_panel",
        &TimePanelBlueprint::new().with_timeline("sim_time"),
    )?;
    let messages = storage.take();
    let Some(blueprint_id) = messages.first().map(|m| m.store_id().clone()) else {
        return Ok(());
    };
    target.send_blueprint(
        messages,
        BlueprintActivationCommand {
            blueprint_id,
            make_active: true,
            make_default: true,
        },
    );
    Ok(())
}

/// The box to frame: the deformables' box, grown to the colliders right under it (clipped to
/// its horizontal extent, and only those within three of its heights below), so a falling body's
/// landing place is in view while a large ground does not set the zoom.
pub fn framing_box(
    deformables: (Vector, Vector),
    colliders: impl Iterator<Item = (Vector, Vector)>,
    up: usize,
) -> (Vector, Vector) {
    let (mut lo, mut hi) = deformables;
    let (dlo, dhi) = deformables;
    let reach = 3.0 * (dhi[up] - dlo[up]).max(1e-3);
    for (clo, chi) in colliders {
        let overlaps = (0..DIM)
            .filter(|&a| a != up)
            .all(|a| clo[a] <= dhi[a] && chi[a] >= dlo[a]);
        if !overlaps || chi[up] < dlo[up] - reach || clo[up] > dhi[up] {
            continue;
        }
        let mut c_lo = clo.max(dlo);
        let mut c_hi = chi.min(dhi);
        c_lo[up] = chi[up].max(dlo[up] - reach);
        c_hi[up] = chi[up].min(dhi[up]);
        lo = lo.min(c_lo);
        hi = hi.max(c_hi);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_metric_is_in_one_plot() {
        let mut seen: Vec<&str> = PLOTS
            .iter()
            .flat_map(|(_, plots)| plots.iter().flat_map(|(_, m)| m.iter().copied()))
            .collect();
        let n = seen.len();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), n, "a metric in two plots");
        for m in super::super::METRICS {
            assert!(seen.contains(m), "{m} is in no plot");
        }
        assert_eq!(seen.len(), super::super::METRICS.len());
    }

    #[test]
    fn ids_round_trip_through_text() {
        let mut ids = Ids(41);
        let b = ids.next();
        let text = uuid_text(&b);
        assert_eq!(text.len(), 36);
        assert_eq!(&text[14..15], "4", "version 4: {text}");
        assert_eq!(text.replace('-', "").len(), 32);
        assert_ne!(ids.next(), b);
    }
}
