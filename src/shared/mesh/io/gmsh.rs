//! Gmsh `.msh` files, ASCII, format versions 4.1 and 2.2.
//!
//! # Reading
//! * `$MeshFormat` must come first; versions `4.1` and `2.2` (also `2.0`, `2.1`, which share
//!   2.2's layout) are read; binary files (file type 1) are refused.
//! * `$Nodes`: any node tags (not necessarily `1..n`, in any order, with gaps), in 4.1 any
//!   number of entity blocks, parametric coordinates allowed (skipped). The three coordinates
//!   are read; a 2D read requires z = 0.
//! * `$Elements`: the cells of the mesh's dimension are taken — 4-node tetrahedra (type 4) or
//!   8-node hexahedra (type 5) in 3D, 3-node triangles (type 2) or 4-node quads (type 3) in
//!   2D, one kind per file. Lower-dimensional elements (boundary triangles and lines, points)
//!   are skipped; higher-order or other elements of the mesh's dimension (10-node tetrahedra,
//!   prisms...) and elements of a higher dimension are refused.
//! * Every other section (`$Entities`, `$PhysicalNames`, `$NodeData`, `$Comments`...) is
//!   skipped up to its `$End...` line.
//! * Cells are reoriented to positive volume if needed (Gmsh's tetrahedra can come either
//!   way) and unused nodes dropped: see [the module](super).
//!
//! # Writing
//! [`write()`] produces 4.1 (one entity of the mesh's dimension holding every node and cell)
//! or 2.2, node tags `1..n` in mesh order, reals written so that they read back exactly.
//!
//! ```
//! use sinew::dim3::{CellKind, Mesh};
//! use sinew::dim3::math::Vector;
//! use sinew::dim3::mesh::io::gmsh::{self, GmshVersion};
//!
//! let mesh = Mesh::cuboid(Vector::splat(0.5), [3, 3, 3], CellKind::Simplex).unwrap();
//! let text = gmsh::to_string(&mesh, GmshVersion::V4_1);
//! let back = gmsh::read_str(&text).unwrap();
//! assert_eq!(back.nodes(), mesh.nodes());
//! assert_eq!(back.cell_indices(), mesh.cell_indices());
//! ```

use std::collections::HashMap;
use std::io::Write;

use super::super::super::math::{Real, DIM, DIM_NAME};
use super::super::{CellKind, Mesh};
use super::{fmt_real, reserve, shorten, xyz, Cursor, Location, Raw, ReadError};

/// The `.msh` format version to write.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub enum GmshVersion {
    /// Format 4.1 (Gmsh 4's default).
    #[default]
    V4_1,
    /// Format 2.2 (the legacy format many tools still read).
    V2_2,
}

one_file_readers!(".msh");

#[derive(Copy, Clone, PartialEq, Eq)]
enum Version {
    V2,
    V4,
}

const SUPPORTED: &str = "ASCII 4.1 and 2.2";

fn parse(text: &str, file: &str) -> Result<Mesh, ReadError> {
    let mut c = Cursor::new(text, file, None);
    c.line("$MeshFormat")?;
    let head = c.field("$MeshFormat")?;
    if head != "$MeshFormat" {
        return Err(c.syntax("$MeshFormat on the first line", head));
    }
    c.line("the format line (version, file type, data size)")?;
    let v = c.field("the version")?;
    let version = match v {
        "4.1" => Version::V4,
        "2.2" | "2.1" | "2" | "2.0" => Version::V2,
        _ => {
            return Err(ReadError::Version {
                at: c.at(),
                found: shorten(v),
                supported: SUPPORTED,
            })
        }
    };
    let file_type = c.field("the file type (0: ASCII)")?;
    match file_type {
        "0" => {}
        "1" => {
            return Err(ReadError::Unsupported {
                at: c.at(),
                what: "binary .msh (file type 1); save as ASCII".into(),
            })
        }
        t => return Err(c.syntax("the file type 0 (ASCII)", t)),
    }
    let size = c.field("the data size")?;
    c.count(size, "a data size")?;
    c.end_of_line("the format line")?;
    expect_end(&mut c, "$EndMeshFormat")?;

    let mut raw = Raw::new(file);
    let mut tags: Option<HashMap<u64, u32>> = None;
    let mut elements = false;
    while c.next_line() {
        let head = c.field("a section")?;
        match head {
            "$Nodes" => {
                if tags.is_some() {
                    return Err(c.syntax("one $Nodes section", head));
                }
                tags = Some(match version {
                    Version::V4 => nodes_v4(&mut c, &mut raw)?,
                    Version::V2 => nodes_v2(&mut c, &mut raw)?,
                });
                expect_end(&mut c, "$EndNodes")?;
            }
            "$Elements" => {
                let Some(tags) = &tags else {
                    return Err(c.syntax("$Nodes before $Elements", head));
                };
                if elements {
                    return Err(c.syntax("one $Elements section", head));
                }
                match version {
                    Version::V4 => elements_v4(&mut c, &mut raw, tags)?,
                    Version::V2 => elements_v2(&mut c, &mut raw, tags)?,
                }
                expect_end(&mut c, "$EndElements")?;
                elements = true;
            }
            s if s.starts_with('$') && !s.starts_with("$End") => skip_section(&mut c, s)?,
            s => return Err(c.syntax("a section ($Nodes, $Elements...)", s)),
        }
    }
    if tags.is_none() {
        return Err(c.truncated("a $Nodes section"));
    }
    if !elements {
        return Err(c.truncated("an $Elements section"));
    }
    raw.end_line = c.at().line.unwrap_or(1);
    raw.finish()
}

fn expect_end(c: &mut Cursor<'_>, end: &str) -> Result<(), ReadError> {
    c.line(end)?;
    let t = c.field(end)?;
    if t != end {
        let at = c.at();
        // A record where the section should end: the header declared too few.
        return Err(if t.starts_with('$') {
            ReadError::Syntax {
                at,
                expected: end.to_owned(),
                found: shorten(t),
            }
        } else {
            ReadError::Count {
                at,
                what: format!(
                    "`{}` where {end} should be: more records than the header declares",
                    shorten(t)
                ),
            }
        });
    }
    c.end_of_line(end)
}

fn skip_section(c: &mut Cursor<'_>, head: &str) -> Result<(), ReadError> {
    let end = format!("$End{}", &head[1..]);
    let start = c.at().line.unwrap_or(1);
    while c.next_line() {
        if c.field("")? == end {
            return Ok(());
        }
    }
    Err(ReadError::Truncated {
        at: c.at(),
        expected: format!("{end} to close {head} (line {start})"),
    })
}

fn node_coordinates(c: &mut Cursor<'_>, raw: &mut Raw) -> Result<(), ReadError> {
    let mut xyz: [Real; 3] = [0.0; 3];
    for v in &mut xyz {
        let t = c.field("three coordinates")?;
        *v = c.real(t)?;
    }
    raw.nodes.push(c.point(xyz)?);
    raw.node_lines.push(c.at().line.unwrap_or(1));
    Ok(())
}

fn add_tag(
    c: &Cursor<'_>,
    tags: &mut HashMap<u64, u32>,
    tag: u64,
    index: usize,
) -> Result<(), ReadError> {
    let Ok(index) = u32::try_from(index) else {
        return Err(ReadError::Count {
            at: c.at(),
            what: "more than 2^32 nodes".into(),
        });
    };
    if tags.insert(tag, index).is_some() {
        return Err(ReadError::Index {
            at: c.at(),
            index: tag,
            reason: "node tag used twice".into(),
        });
    }
    Ok(())
}

fn nodes_v2(c: &mut Cursor<'_>, raw: &mut Raw) -> Result<HashMap<u64, u32>, ReadError> {
    c.line("the number of nodes")?;
    let t = c.field("the number of nodes")?;
    let n = c.count(t, "a node count")?;
    c.end_of_line("the number of nodes")?;
    let mut tags = HashMap::with_capacity(reserve(n));
    for i in 0..n {
        c.record_line("node", i, n)?;
        let t = c.field("the node tag")?;
        let tag = c.uint(t, "a node tag (non-negative integer)")?;
        add_tag(c, &mut tags, tag, raw.nodes.len())?;
        node_coordinates(c, raw)?;
        c.end_of_line("a node's tag and coordinates")?;
    }
    Ok(tags)
}

fn nodes_v4(c: &mut Cursor<'_>, raw: &mut Raw) -> Result<HashMap<u64, u32>, ReadError> {
    c.line("the $Nodes header")?;
    let t = c.field("the number of entity blocks")?;
    let blocks = c.count(t, "a block count")?;
    let t = c.field("the number of nodes")?;
    let n = c.count(t, "a node count")?;
    for what in ["the smallest node tag", "the largest node tag"] {
        let t = c.field(what)?;
        c.uint(t, "a node tag (non-negative integer)")?;
    }
    c.end_of_line("the $Nodes header")?;
    let header = c.at().line.unwrap_or(1);
    let mut tags = HashMap::with_capacity(reserve(n));
    let mut block_tags = Vec::new();
    for b in 0..blocks {
        c.record_line("node block", b, blocks)?;
        let t = c.field("the entity dimension")?;
        let entity_dim = c.count(t, "an entity dimension (0 to 3)")?;
        let t = c.field("the entity tag")?;
        t.parse::<i64>().map_err(|_| ReadError::Number {
            at: c.at(),
            token: shorten(t),
            expected: "an entity tag (integer)",
        })?;
        let t = c.field("the parametric flag")?;
        let parametric = match t {
            "0" => false,
            "1" => true,
            t => return Err(c.syntax("the parametric flag 0 or 1", t)),
        };
        let t = c.field("the number of nodes in the block")?;
        let m = c.count(t, "a node count")?;
        c.end_of_line("the node block header")?;
        if raw.nodes.len().saturating_add(m) > n {
            return Err(ReadError::Count {
                at: c.at(),
                what: format!(
                    "the blocks hold more than the {n} nodes the header (line {header}) declares"
                ),
            });
        }
        block_tags.clear();
        for i in 0..m {
            c.record_line("node tag", i, m)?;
            let t = c.field("a node tag")?;
            block_tags.push((c.uint(t, "a node tag (non-negative integer)")?, c.at()));
            c.end_of_line("a node tag")?;
        }
        for (i, (tag, at)) in block_tags.iter().enumerate() {
            c.record_line("node coordinate line", i, m)?;
            if tags.insert(*tag, raw.nodes.len() as u32).is_some() {
                return Err(ReadError::Index {
                    at: at.clone(),
                    index: *tag,
                    reason: "node tag used twice".into(),
                });
            }
            node_coordinates(c, raw)?;
            let extra = c.rest_count();
            let allowed = if parametric { entity_dim } else { 0 };
            if extra != allowed {
                return Err(ReadError::Count {
                    at: c.at(),
                    what: format!(
                        "{} values on a coordinate line, expected {}",
                        extra.saturating_add(3),
                        allowed.saturating_add(3)
                    ),
                });
            }
        }
    }
    if raw.nodes.len() != n {
        return Err(ReadError::Count {
            at: c.at_line(header),
            what: format!(
                "the header declares {n} nodes, the blocks hold {}",
                raw.nodes.len()
            ),
        });
    }
    Ok(tags)
}

/// The dimension of a Gmsh element type, and for the types taken, the cell kind.
fn element_type(ty: u64) -> Option<(usize, Option<CellKind>)> {
    let dim = match ty {
        15 => 0,
        1 | 8 | 26 | 27 | 28 => 1,
        2 | 3 | 9 | 10 | 16 | 20..=25 => 2,
        4..=7 | 11..=14 | 17..=19 | 29..=31 | 92 | 93 => 3,
        _ => return None,
    };
    let kind = match (ty, DIM) {
        (2, 2) | (4, 3) => Some(CellKind::Simplex),
        (3, 2) | (5, 3) => Some(CellKind::Cube),
        _ => None,
    };
    Some((dim, kind))
}

/// Checks an element of dimension `dim` and type `ty`: `Ok(None)` to skip it, the kind to
/// take it, or the error.
fn classify(c: &Cursor<'_>, ty: u64, dim: Option<usize>) -> Result<Option<CellKind>, ReadError> {
    let Some((type_dim, kind)) = element_type(ty) else {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: format!("unknown Gmsh element type {ty}"),
        });
    };
    let dim = dim.unwrap_or(type_dim);
    if dim < DIM {
        return Ok(None);
    }
    if dim > DIM {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: format!("{dim}D elements (type {ty}) in a {DIM_NAME} read"),
        });
    }
    match kind {
        Some(k) if type_dim == dim => Ok(Some(k)),
        _ => Err(ReadError::Unsupported {
            at: c.at(),
            what: format!(
                "Gmsh element type {ty}: a {DIM_NAME} read takes linear {} (type {}) or {} (type {})",
                super::plural(CellKind::Simplex),
                if DIM == 2 { 2 } else { 4 },
                super::plural(CellKind::Cube),
                if DIM == 2 { 3 } else { 5 },
            ),
        }),
    }
}

/// Reads the `arity` node tags of a cell on the current line and stores the cell.
fn cell_nodes(
    c: &mut Cursor<'_>,
    raw: &mut Raw,
    tags: &HashMap<u64, u32>,
    kind: CellKind,
) -> Result<(), ReadError> {
    raw.set_kind(kind, c.at())?;
    let arity = kind.arity();
    for k in 0..arity {
        let t = c.field_with(|| format!("node {} of {arity} of the {}", k + 1, kind.name()))?;
        let tag = c.uint(t, "a node tag (non-negative integer)")?;
        let Some(&i) = tags.get(&tag) else {
            return Err(ReadError::Index {
                at: c.at(),
                index: tag,
                reason: "no node has this tag in $Nodes".into(),
            });
        };
        raw.cells.push(i);
    }
    c.end_of_line_with(|| format!("the {arity} nodes of a {}", kind.name()))?;
    raw.cell_lines.push(c.at().line.unwrap_or(1));
    Ok(())
}

fn elements_v2(
    c: &mut Cursor<'_>,
    raw: &mut Raw,
    tags: &HashMap<u64, u32>,
) -> Result<(), ReadError> {
    c.line("the number of elements")?;
    let t = c.field("the number of elements")?;
    let n = c.count(t, "an element count")?;
    c.end_of_line("the number of elements")?;
    for i in 0..n {
        c.record_line("element", i, n)?;
        let t = c.field("the element tag")?;
        c.uint(t, "an element tag (non-negative integer)")?;
        let t = c.field("the element type")?;
        let ty = c.uint(t, "an element type (positive integer)")?;
        let t = c.field("the number of element tags")?;
        let ntags = c.count(t, "a tag count")?;
        for _ in 0..ntags {
            let t = c.field("an element tag")?;
            t.parse::<i64>().map_err(|_| ReadError::Number {
                at: c.at(),
                token: shorten(t),
                expected: "an element tag (integer)",
            })?;
        }
        match classify(c, ty, None)? {
            None => {
                c.rest_count();
            }
            Some(kind) => cell_nodes(c, raw, tags, kind)?,
        }
    }
    Ok(())
}

fn elements_v4(
    c: &mut Cursor<'_>,
    raw: &mut Raw,
    tags: &HashMap<u64, u32>,
) -> Result<(), ReadError> {
    c.line("the $Elements header")?;
    let t = c.field("the number of entity blocks")?;
    let blocks = c.count(t, "a block count")?;
    let t = c.field("the number of elements")?;
    let n = c.count(t, "an element count")?;
    for what in ["the smallest element tag", "the largest element tag"] {
        let t = c.field(what)?;
        c.uint(t, "an element tag (non-negative integer)")?;
    }
    c.end_of_line("the $Elements header")?;
    let header = c.at().line.unwrap_or(1);
    let mut total = 0usize;
    for b in 0..blocks {
        c.record_line("element block", b, blocks)?;
        let t = c.field("the entity dimension")?;
        let dim = c.count(t, "an entity dimension (0 to 3)")?;
        let t = c.field("the entity tag")?;
        t.parse::<i64>().map_err(|_| ReadError::Number {
            at: c.at(),
            token: shorten(t),
            expected: "an entity tag (integer)",
        })?;
        let t = c.field("the element type")?;
        let ty = c.uint(t, "an element type (positive integer)")?;
        let t = c.field("the number of elements in the block")?;
        let m = c.count(t, "an element count")?;
        c.end_of_line("the element block header")?;
        total = total.saturating_add(m);
        if total > n {
            return Err(ReadError::Count {
                at: c.at(),
                what: format!(
                    "the blocks hold more than the {n} elements the header (line {header}) declares"
                ),
            });
        }
        let kind = classify(c, ty, Some(dim))?;
        for i in 0..m {
            c.record_line("element", i, m)?;
            let t = c.field("the element tag")?;
            c.uint(t, "an element tag (non-negative integer)")?;
            match kind {
                None => {
                    c.rest_count();
                }
                Some(kind) => cell_nodes(c, raw, tags, kind)?,
            }
        }
    }
    if total != n {
        return Err(ReadError::Count {
            at: Location {
                file: raw.file.clone(),
                line: Some(header),
            },
            what: format!("the header declares {n} elements, the blocks hold {total}"),
        });
    }
    Ok(())
}

fn type_of(kind: CellKind) -> u32 {
    match (kind, DIM) {
        (CellKind::Simplex, 2) => 2,
        (CellKind::Simplex, _) => 4,
        (CellKind::Cube, 2) => 3,
        (CellKind::Cube, _) => 5,
    }
}

/// Writes `mesh` as an ASCII `.msh` file of the given version (node and element tags
/// `1..n`, one physical-free entity of the mesh's dimension in 4.1).
pub fn write(mesh: &Mesh, version: GmshVersion, mut out: impl Write) -> std::io::Result<()> {
    let n = mesh.nodes().len();
    let m = mesh.num_cells();
    let ty = type_of(mesh.kind());
    let node_line = |out: &mut dyn Write, p| -> std::io::Result<()> {
        let [x, y, z] = xyz(p);
        writeln!(out, "{} {} {}", fmt_real(x), fmt_real(y), fmt_real(z))
    };
    match version {
        GmshVersion::V4_1 => {
            writeln!(out, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
            // One entity of the mesh's dimension, with its bounding box.
            let mut lo = [Real::INFINITY; 3];
            let mut hi = [Real::NEG_INFINITY; 3];
            for &p in mesh.nodes() {
                for (d, v) in xyz(p).into_iter().enumerate() {
                    lo[d] = lo[d].min(v);
                    hi[d] = hi[d].max(v);
                }
            }
            let counts = if DIM == 2 { "0 0 1 0" } else { "0 0 0 1" };
            writeln!(out, "$Entities\n{counts}")?;
            write!(out, "1")?;
            for v in lo.iter().chain(&hi) {
                write!(out, " {}", fmt_real(*v))?;
            }
            writeln!(out, " 0 0\n$EndEntities")?;
            writeln!(out, "$Nodes\n1 {n} 1 {n}\n{DIM} 1 0 {n}")?;
            for i in 1..=n {
                writeln!(out, "{i}")?;
            }
            for &p in mesh.nodes() {
                node_line(&mut out, p)?;
            }
            writeln!(out, "$EndNodes")?;
            writeln!(out, "$Elements\n1 {m} 1 {m}\n{DIM} 1 {ty} {m}")?;
            for (k, cell) in mesh.cells().enumerate() {
                write!(out, "{}", k + 1)?;
                for &i in cell {
                    write!(out, " {}", i + 1)?;
                }
                writeln!(out)?;
            }
            writeln!(out, "$EndElements")?;
        }
        GmshVersion::V2_2 => {
            writeln!(out, "$MeshFormat\n2.2 0 8\n$EndMeshFormat")?;
            writeln!(out, "$Nodes\n{n}")?;
            for (i, &p) in mesh.nodes().iter().enumerate() {
                write!(out, "{} ", i + 1)?;
                node_line(&mut out, p)?;
            }
            writeln!(out, "$EndNodes")?;
            writeln!(out, "$Elements\n{m}")?;
            for (k, cell) in mesh.cells().enumerate() {
                // Two tags: physical group 0, elementary entity 1.
                write!(out, "{} {ty} 2 0 1", k + 1)?;
                for &i in cell {
                    write!(out, " {}", i + 1)?;
                }
                writeln!(out)?;
            }
            writeln!(out, "$EndElements")?;
        }
    }
    Ok(())
}

/// [`write()`] into a string.
pub fn to_string(mesh: &Mesh, version: GmshVersion) -> String {
    let mut out = Vec::new();
    // Writing into a Vec cannot fail, and the text is ASCII.
    let _ = write(mesh, version, &mut out);
    String::from_utf8_lossy(&out).into_owned()
}
