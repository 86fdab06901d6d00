//! TetGen `.node` + `.ele` files (3D) and Triangle's files of the same format (2D).
//!
//! # Reading
//! * `.node`: a header `<points> <dimension> <attributes> <boundary markers 0|1>`, then one
//!   line per point `<number> <x> <y> [<z>] [attributes...] [marker]`. The dimension must be
//!   the mesh's (3 for TetGen, 2 for Triangle). Point numbers start at 0 or 1 (taken from the
//!   first point) and run consecutively.
//! * `.ele`: a header `<cells> <nodes per cell> <attributes>`, then one line per cell
//!   `<number> <nodes...> [attributes...]`. Linear cells (4 nodes in 3D, 3 in 2D) and
//!   quadratic ones (10 / 6 nodes) are read; of a quadratic cell only the corners (its first
//!   nodes) are kept, and the edge nodes then used by no cell are dropped.
//! * `#` starts a comment anywhere; blank lines are skipped. Every line must hold exactly the
//!   number of values its header announces, and the files must hold exactly the number of
//!   records announced.
//! * Cells are reoriented to positive volume if needed and unused nodes dropped: see [the
//!   module](super).
//!
//! # Writing
//! [`write()`] numbers points and cells from 1, no attributes, no markers. Box meshes cannot be
//! written (the format holds simplices only).

use std::io::{BufRead, Write};
use std::path::Path;

use super::super::super::math::{DIM, DIM_NAME, SIMPLEX_ARITY};
use super::super::{CellKind, Mesh};
use super::{fmt_real, load_path, load_reader, reserve, Cursor, Raw, ReadError};

/// Reads a `.node` and an `.ele` file.
pub fn read(node_path: impl AsRef<Path>, ele_path: impl AsRef<Path>) -> Result<Mesh, ReadError> {
    let (node_file, node) = load_path(node_path.as_ref())?;
    let (ele_file, ele) = load_path(ele_path.as_ref())?;
    parse(&node, &node_file, &ele, &ele_file)
}

/// Reads `.node` and `.ele` text; errors name the files `<memory>.node` and `<memory>.ele`.
pub fn read_str(node: &str, ele: &str) -> Result<Mesh, ReadError> {
    parse(node, NODE_MEMORY, ele, ELE_MEMORY)
}

/// Reads `.node` and `.ele` text from readers; errors name the files `<memory>.node` and
/// `<memory>.ele`.
pub fn read_from(node: impl BufRead, ele: impl BufRead) -> Result<Mesh, ReadError> {
    let node = load_reader(node, NODE_MEMORY)?;
    let ele = load_reader(ele, ELE_MEMORY)?;
    parse(&node, NODE_MEMORY, &ele, ELE_MEMORY)
}

const NODE_MEMORY: &str = "<memory>.node";
const ELE_MEMORY: &str = "<memory>.ele";

/// Nodes per cell of the quadratic simplex (TetGen `-o2`, Triangle `-o2`).
const QUADRATIC_ARITY: usize = if DIM == 2 { 6 } else { 10 };

fn parse(node: &str, node_file: &str, ele: &str, ele_file: &str) -> Result<Mesh, ReadError> {
    let mut raw = Raw::new(ele_file);
    let mut node_lines = Vec::new();
    let base = parse_node(node, node_file, &mut raw, &mut node_lines)?;
    let n = raw.nodes.len();

    let mut c = Cursor::new(ele, ele_file, Some('#'));
    c.line("the .ele header (cells, nodes per cell, attributes)")?;
    let t = c.field("the number of cells")?;
    let m = c.count(t, "a cell count")?;
    let t = c.field("the number of nodes per cell")?;
    let per_cell = c.count(t, "a node count")?;
    let t = c.field("the number of attributes")?;
    let attributes = c.count(t, "an attribute count")?;
    c.end_of_line("the .ele header")?;
    if per_cell != SIMPLEX_ARITY && per_cell != QUADRATIC_ARITY {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: format!(
                "{per_cell} nodes per cell: a {DIM_NAME} read takes {SIMPLEX_ARITY} or \
                 {QUADRATIC_ARITY} (quadratic, corners kept)"
            ),
        });
    }
    raw.cells.reserve(reserve(m) * SIMPLEX_ARITY);
    for i in 0..m {
        c.record_line("cell", i, m)?;
        let t = c.field("the cell number")?;
        c.uint(t, "a cell number (non-negative integer)")?;
        for k in 0..per_cell {
            let t = c.field_with(|| format!("node {} of {per_cell}", k + 1))?;
            let index = c.uint(t, "a node number (non-negative integer)")?;
            let local = index.checked_sub(base).filter(|&l| l < n as u64);
            let Some(local) = local else {
                return Err(ReadError::Index {
                    at: c.at(),
                    index,
                    reason: format!(
                        "the .node file numbers its {n} points from {base} to {}",
                        (base + n as u64).saturating_sub(1)
                    ),
                });
            };
            if k < SIMPLEX_ARITY {
                raw.cells.push(local as u32);
            }
        }
        for k in 0..attributes {
            let t = c.field_with(|| format!("attribute {} of {attributes}", k + 1))?;
            c.real(t)?;
        }
        c.end_of_line("the cell's nodes and attributes")?;
        raw.cell_lines.push(c.at().line.unwrap_or(1));
    }
    if c.next_line() {
        return Err(ReadError::Count {
            at: c.at(),
            what: format!("more lines than the {m} cells the header declares"),
        });
    }
    raw.kind = (m > 0).then_some(CellKind::Simplex);
    raw.end_line = c.at().line.unwrap_or(1);
    raw.node_lines = node_lines;
    // Node errors name the .node file.
    let node_file = node_file.to_owned();
    raw.finish().map_err(|e| match e {
        ReadError::Mesh { at, source }
            if matches!(
                source,
                super::super::super::error::BuildError::NonFiniteCoordinate { .. }
                    | super::super::super::error::BuildError::UnreferencedNode { .. }
            ) =>
        {
            ReadError::Mesh {
                at: super::Location {
                    file: node_file,
                    line: at.line,
                },
                source,
            }
        }
        e => e,
    })
}

/// Parses the `.node` file into `raw.nodes`; returns the number of the first point.
fn parse_node(
    text: &str,
    file: &str,
    raw: &mut Raw,
    lines: &mut Vec<usize>,
) -> Result<u64, ReadError> {
    let mut c = Cursor::new(text, file, Some('#'));
    c.line("the .node header (points, dimension, attributes, markers)")?;
    let t = c.field("the number of points")?;
    let n = c.count(t, "a point count")?;
    let t = c.field("the dimension")?;
    let dim = c.count(t, "a dimension (2 or 3)")?;
    let t = c.field("the number of attributes")?;
    let attributes = c.count(t, "an attribute count")?;
    let t = c.field("the number of boundary markers (0 or 1)")?;
    let markers = c.count(t, "a marker count (0 or 1)")?;
    c.end_of_line("the .node header")?;
    if dim != DIM {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: format!("a {dim}-dimensional .node file in a {DIM_NAME} read"),
        });
    }
    if markers > 1 {
        return Err(ReadError::Count {
            at: c.at(),
            what: format!("{markers} boundary markers per point (0 or 1)"),
        });
    }
    if n == 0 {
        return Err(ReadError::Count {
            at: c.at(),
            what: "no points (points listed in a .poly file are not read)".into(),
        });
    }
    raw.nodes.reserve(reserve(n));
    let mut base = 0u64;
    for i in 0..n {
        c.record_line("point", i, n)?;
        let t = c.field("the point number")?;
        let number = c.uint(t, "a point number (non-negative integer)")?;
        if i == 0 {
            if number > 1 {
                return Err(ReadError::Index {
                    at: c.at(),
                    index: number,
                    reason: "the first point must be numbered 0 or 1".into(),
                });
            }
            base = number;
        } else if number != base + i as u64 {
            return Err(ReadError::Index {
                at: c.at(),
                index: number,
                reason: format!(
                    "points must be numbered consecutively: expected {}",
                    base + i as u64
                ),
            });
        }
        let mut xyz = [0.0; 3];
        for v in xyz.iter_mut().take(DIM) {
            let t = c.field_with(|| format!("{DIM} coordinates"))?;
            *v = c.real(t)?;
        }
        for k in 0..attributes {
            let t = c.field_with(|| format!("attribute {} of {attributes}", k + 1))?;
            c.real(t)?;
        }
        if markers == 1 {
            let t = c.field("the boundary marker")?;
            t.parse::<i64>().map_err(|_| ReadError::Number {
                at: c.at(),
                token: super::shorten(t),
                expected: "a boundary marker (integer)",
            })?;
        }
        c.end_of_line("the point's coordinates, attributes and marker")?;
        raw.nodes.push(c.point(xyz)?);
        lines.push(c.at().line.unwrap_or(1));
    }
    if c.next_line() {
        return Err(ReadError::Count {
            at: c.at(),
            what: format!("more lines than the {n} points the header declares"),
        });
    }
    Ok(base)
}

/// Writes `mesh` as `.node` and `.ele` text, numbered from 1. Fails with
/// [`std::io::ErrorKind::InvalidInput`] for a box mesh.
pub fn write(mesh: &Mesh, mut node: impl Write, mut ele: impl Write) -> std::io::Result<()> {
    if mesh.kind() != CellKind::Simplex {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "TetGen / Triangle files hold simplices only",
        ));
    }
    writeln!(node, "# written by sinew\n{} {DIM} 0 0", mesh.nodes().len())?;
    for (i, p) in mesh.nodes().iter().enumerate() {
        write!(node, "{}", i + 1)?;
        for d in 0..DIM {
            write!(node, " {}", fmt_real(p[d]))?;
        }
        writeln!(node)?;
    }
    writeln!(
        ele,
        "# written by sinew\n{} {SIMPLEX_ARITY} 0",
        mesh.num_cells()
    )?;
    for (k, cell) in mesh.cells().enumerate() {
        write!(ele, "{}", k + 1)?;
        for &i in cell {
            write!(ele, " {}", i + 1)?;
        }
        writeln!(ele)?;
    }
    Ok(())
}

/// [`write()`] into two strings (`.node`, `.ele`); `None` for a box mesh.
pub fn to_strings(mesh: &Mesh) -> Option<(String, String)> {
    let mut node = Vec::new();
    let mut ele = Vec::new();
    write(mesh, &mut node, &mut ele).ok()?;
    Some((
        String::from_utf8_lossy(&node).into_owned(),
        String::from_utf8_lossy(&ele).into_owned(),
    ))
}
