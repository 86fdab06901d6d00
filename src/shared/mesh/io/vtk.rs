//! Legacy VTK files (`.vtk`), ASCII, `DATASET UNSTRUCTURED_GRID`.
//!
//! # Reading
//! * The header `# vtk DataFile Version x.y` (versions 1.0 to 5.1), a title line, `ASCII`
//!   (binary files are refused), `DATASET UNSTRUCTURED_GRID` (other datasets are refused).
//! * `POINTS n <type>`: `3n` coordinates, in any line layout. A 2D read takes x and y and
//!   requires z = 0: a point off the plane is an error ([`ReadError::OutOfPlane`]) rather
//!   than silently projected.
//! * `CELLS`: the classic layout (`CELLS n size`, then per cell its node count and nodes,
//!   `size` values in all) and the 5.1 layout (`CELLS offsets connectivity`, then `OFFSETS`
//!   and `CONNECTIVITY` arrays).
//! * `CELL_TYPES n`: one type per cell. Taken: tetrahedra (10) and hexahedra (12; voxels, 11,
//!   reordered) in 3D, triangles (5) and quads (9; pixels, 8, reordered) in 2D, one kind per
//!   file. Lower-dimensional cells are skipped; other cells of the mesh's dimension (wedges,
//!   quadratic cells...) and cells of a higher dimension are refused.
//! * `FIELD` blocks before the geometry are skipped; reading stops at `POINT_DATA` or
//!   `CELL_DATA`.
//! * Cells are reoriented to positive volume if needed and unused nodes dropped: see [the
//!   module](super).
//!
//! # Writing
//! [`write()`] produces version 3.0 (classic `CELLS`), points as `float` written so that they
//! read back exactly (z = 0 in 2D).

use std::io::Write;

use super::super::super::math::{Real, DIM, DIM_NAME};
use super::super::cube::{bits_to_vtk, vtk_to_bits, CUBE_ARITY};
use super::super::{CellKind, Mesh};
use super::{fmt_real, plural, reserve, shorten, xyz, Cursor, Location, Raw, ReadError};

one_file_readers!(".vtk");

const SUPPORTED: &str = "legacy ASCII 1.0 to 5.1";
const HEADER: &str = "# vtk DataFile Version";

/// The dimension of a VTK cell type, and for the types taken, the cell kind and whether the
/// corners come in bit order (voxel, pixel) rather than VTK's box order.
fn cell_type(ty: u64) -> Option<(usize, Option<(CellKind, bool)>)> {
    let dim = match ty {
        0..=2 => 0,
        3 | 4 | 21 | 35 | 68 | 75 => 1,
        5..=9 | 22 | 23 | 28 | 30 | 34 | 36 | 69 | 70 | 76 | 77 => 2,
        10..=16 | 24..=27 | 29 | 31..=33 | 37 | 42 | 71..=74 | 78..=81 => 3,
        _ => return None,
    };
    let kind = match (ty, DIM) {
        (5, 2) | (10, 3) => Some((CellKind::Simplex, false)),
        (9, 2) | (12, 3) => Some((CellKind::Cube, false)),
        (8, 2) | (11, 3) => Some((CellKind::Cube, true)),
        _ => None,
    };
    Some((dim, kind))
}

struct Cells {
    /// Per cell: the range of its nodes in `connectivity`, and its line.
    ranges: Vec<(usize, usize, usize)>,
    connectivity: Vec<u64>,
}

// long-fn: a parser, one pass over the file's sections in the order the format puts them, each
// error naming the line it is read at; split, it would pass the cursor and half-read state
// around.
fn parse(text: &str, file: &str) -> Result<Mesh, ReadError> {
    let mut c = Cursor::new(text, file, None);
    let Some(first) = c.raw_line() else {
        return Err(c.truncated("the header `# vtk DataFile Version x.y`"));
    };
    let first = first.trim();
    let Some(version) = first
        .get(..HEADER.len())
        .filter(|h| h.eq_ignore_ascii_case(HEADER))
        .map(|_| first[HEADER.len()..].trim())
    else {
        return Err(c.syntax("the header `# vtk DataFile Version x.y`", first));
    };
    let major = version
        .split('.')
        .next()
        .and_then(|m| m.parse::<u32>().ok());
    if !matches!(major, Some(1..=5)) {
        return Err(ReadError::Version {
            at: c.at(),
            found: shorten(version),
            supported: SUPPORTED,
        });
    }
    if c.raw_line().is_none() {
        return Err(c.truncated("the title line"));
    }
    c.line("ASCII or BINARY")?;
    let t = c.field("ASCII")?;
    if t.eq_ignore_ascii_case("BINARY") {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: "binary VTK; save as ASCII".into(),
        });
    }
    if !t.eq_ignore_ascii_case("ASCII") {
        return Err(c.syntax("ASCII", t));
    }
    c.keyword("DATASET", "DATASET UNSTRUCTURED_GRID")?;
    let t = c.token("the dataset type")?;
    if !t.eq_ignore_ascii_case("UNSTRUCTURED_GRID") {
        return Err(ReadError::Unsupported {
            at: c.at(),
            what: format!(
                "dataset `{}`: only UNSTRUCTURED_GRID holds cells",
                shorten(t)
            ),
        });
    }

    let mut raw = Raw::new(file);
    let mut cells: Option<Cells> = None;
    let mut types: Option<(Vec<(u64, usize)>, usize)> = None;
    let mut have_points = false;
    while let Ok(word) = c.token("") {
        match word.to_ascii_uppercase().as_str() {
            "POINTS" if !have_points => {
                points(&mut c, &mut raw)?;
                have_points = true;
            }
            "CELLS" if cells.is_none() => cells = Some(read_cells(&mut c)?),
            "CELL_TYPES" if types.is_none() => {
                let header = c.at().line.unwrap_or(1);
                let t = c.token("the number of cell types")?;
                let n = c.count(t, "a cell count")?;
                let mut v = Vec::with_capacity(reserve(n));
                for _ in 0..n {
                    let t = c.token("a cell type")?;
                    v.push((
                        c.uint(t, "a cell type (non-negative integer)")?,
                        c.at().line.unwrap_or(1),
                    ));
                }
                types = Some((v, header));
            }
            "FIELD" => skip_field(&mut c)?,
            "POINT_DATA" | "CELL_DATA" => break,
            _ if word.parse::<f64>().is_ok() => {
                return Err(ReadError::Count {
                    at: c.at(),
                    what: format!(
                        "`{}` where a keyword should be: the section before holds more values \
                         than its header declares",
                        shorten(word)
                    ),
                })
            }
            _ => {
                return Err(c.syntax(
                    "POINTS, CELLS, CELL_TYPES, FIELD, POINT_DATA or CELL_DATA (each once)",
                    word,
                ))
            }
        }
    }
    raw.end_line = c.at().line.unwrap_or(1);
    if !have_points {
        return Err(c.truncated("a POINTS section"));
    }
    let Some(cells) = cells else {
        return Err(c.truncated("a CELLS section"));
    };
    let Some((types, types_line)) = types else {
        return Err(c.truncated("a CELL_TYPES section"));
    };
    if types.len() != cells.ranges.len() {
        return Err(ReadError::Count {
            at: Location {
                file: file.to_owned(),
                line: Some(types_line),
            },
            what: format!(
                "CELL_TYPES lists {} types for {} cells",
                types.len(),
                cells.ranges.len()
            ),
        });
    }
    let n = raw.nodes.len();
    for (&(start, end_, line), &(ty, type_line)) in cells.ranges.iter().zip(&types) {
        let at_type = || Location {
            file: file.to_owned(),
            line: Some(type_line),
        };
        let Some((dim, kind)) = cell_type(ty) else {
            return Err(ReadError::Unsupported {
                at: at_type(),
                what: format!("unknown VTK cell type {ty}"),
            });
        };
        if dim < DIM {
            continue;
        }
        let Some((kind, bit_order)) = kind.filter(|_| dim == DIM) else {
            return Err(ReadError::Unsupported {
                at: at_type(),
                what: if dim > DIM {
                    format!("{dim}D cells (type {ty}) in a {DIM_NAME} read")
                } else {
                    format!(
                        "VTK cell type {ty}: a {DIM_NAME} read takes {} ({}) or {} ({})",
                        plural(CellKind::Simplex),
                        if DIM == 2 { 5 } else { 10 },
                        plural(CellKind::Cube),
                        if DIM == 2 { "9, 8" } else { "12, 11" },
                    )
                },
            });
        };
        let at = Location {
            file: file.to_owned(),
            line: Some(line),
        };
        raw.set_kind(kind, at.clone())?;
        let ids = cells.connectivity.get(start..end_).unwrap_or(&[]);
        if ids.len() != kind.arity() {
            return Err(ReadError::Count {
                at,
                what: format!(
                    "a {} (type {ty}) has {} nodes, this cell lists {}",
                    kind.name(),
                    kind.arity(),
                    ids.len()
                ),
            });
        }
        let mut cell = [0u32; CUBE_ARITY];
        for (k, &id) in ids.iter().enumerate() {
            if id >= n as u64 {
                return Err(ReadError::Index {
                    at,
                    index: id,
                    reason: format!(
                        "POINTS holds {n} points (indices 0 to {})",
                        n.saturating_sub(1)
                    ),
                });
            }
            // Voxels and pixels list corners in bit order; the mesh wants VTK box order.
            let slot = if bit_order { bits_to_vtk(k) } else { k };
            cell[slot] = id as u32;
        }
        raw.cells.extend_from_slice(&cell[..kind.arity()]);
        raw.cell_lines.push(line);
    }
    raw.finish()
}

fn points(c: &mut Cursor<'_>, raw: &mut Raw) -> Result<(), ReadError> {
    let t = c.token("the number of points")?;
    let n = c.count(t, "a point count")?;
    let t = c.token("the point data type")?;
    let numeric = [
        "float",
        "double",
        "int",
        "unsigned_int",
        "long",
        "unsigned_long",
        "short",
        "unsigned_short",
        "char",
        "unsigned_char",
        "bit",
        "vtktypeint64",
        "vtktypeuint64",
    ];
    if !numeric.iter().any(|k| t.eq_ignore_ascii_case(k)) {
        return Err(c.syntax("a data type (float, double...)", t));
    }
    raw.nodes.reserve(reserve(n));
    for i in 0..n {
        let mut p: [Real; 3] = [0.0; 3];
        for v in &mut p {
            let t = c.token_with(|| format!("the coordinates of point {} of {n}", i + 1))?;
            *v = c.real(t).map_err(|e| point_count_hint(e, i, n))?;
        }
        raw.nodes.push(c.point(p)?);
        raw.node_lines.push(c.at().line.unwrap_or(1));
    }
    Ok(())
}

const KEYWORDS: [&str; 6] = [
    "CELLS",
    "CELL_TYPES",
    "POINT_DATA",
    "CELL_DATA",
    "FIELD",
    "METADATA",
];

/// A keyword where a coordinate should be means POINTS declared more points than it holds.
fn point_count_hint(e: ReadError, i: usize, n: usize) -> ReadError {
    match e {
        ReadError::Number { at, token, .. }
            if KEYWORDS.iter().any(|k| token.eq_ignore_ascii_case(k)) =>
        {
            ReadError::Count {
                at,
                what: format!("`{token}` after {i} points, but POINTS declares {n}"),
            }
        }
        e => e,
    }
}

fn index(c: &Cursor<'_>, t: &str) -> Result<u64, ReadError> {
    c.uint(t, "a point index (non-negative integer)")
}

fn read_cells(c: &mut Cursor<'_>) -> Result<Cells, ReadError> {
    let header = c.at();
    let t = c.token("the number of cells")?;
    let n = c.count(t, "a cell count")?;
    let t = c.token("the size of the cell list")?;
    let size = c.count(t, "a list size")?;
    let mut cells = Cells {
        ranges: Vec::with_capacity(reserve(n)),
        connectivity: Vec::with_capacity(reserve(size)),
    };
    // 5.1 layout: OFFSETS and CONNECTIVITY arrays.
    let t = c.token("the cell list")?;
    if t.eq_ignore_ascii_case("OFFSETS") {
        c.token("the offsets' data type")?;
        let mut offsets = Vec::with_capacity(reserve(n));
        let mut lines = Vec::with_capacity(reserve(n));
        for _ in 0..n {
            let t = c.token("an offset")?;
            offsets.push(c.count(t, "an offset (non-negative integer)")?);
            lines.push(c.at().line.unwrap_or(1));
        }
        c.keyword("CONNECTIVITY", "CONNECTIVITY")?;
        c.token("the connectivity's data type")?;
        for _ in 0..size {
            let t = c.token("a point index")?;
            cells.connectivity.push(index(c, t)?);
        }
        if offsets.first().is_some_and(|&o| o != 0) || offsets.last().is_some_and(|&o| o != size) {
            return Err(ReadError::Count {
                at: header,
                what: format!("OFFSETS must run from 0 to the connectivity's size {size}"),
            });
        }
        for (k, w) in offsets.windows(2).enumerate() {
            if w[1] < w[0] {
                return Err(ReadError::Count {
                    at: c.at_line(lines.get(k + 1).copied().unwrap_or(1)),
                    what: format!("offset {} is smaller than the one before", w[1]),
                });
            }
            cells
                .ranges
                .push((w[0], w[1], lines.get(k + 1).copied().unwrap_or(1)));
        }
        return Ok(cells);
    }
    // Classic layout: per cell its node count, then its nodes.
    let mut pending = Some(t);
    for i in 0..n {
        let t = match pending.take() {
            Some(t) => t,
            None => c.token_with(|| format!("cell {} of {n}", i + 1))?,
        };
        let k = c.count(t, "a cell's node count (non-negative integer)")?;
        let line = c.at().line.unwrap_or(1);
        let start = cells.connectivity.len();
        if start.saturating_add(k).saturating_add(1).saturating_add(i) > size {
            return Err(ReadError::Count {
                at: c.at(),
                what: format!(
                    "the cells hold more than the {size} values the CELLS header (line {}) declares",
                    header.line.unwrap_or(1)
                ),
            });
        }
        for _ in 0..k {
            let t = c.token("a point index")?;
            cells.connectivity.push(index(c, t)?);
        }
        cells.ranges.push((start, cells.connectivity.len(), line));
    }
    let values = cells.connectivity.len() + n;
    if values != size {
        return Err(ReadError::Count {
            at: header,
            what: format!("CELLS declares {size} values, the {n} cells hold {values}"),
        });
    }
    Ok(cells)
}

/// Skips `FIELD name arrays`, each array `name components tuples type` and its values.
fn skip_field(c: &mut Cursor<'_>) -> Result<(), ReadError> {
    c.token("the field's name")?;
    let t = c.token("the number of arrays")?;
    let arrays = c.count(t, "an array count")?;
    for _ in 0..arrays {
        c.token("an array name")?;
        let t = c.token("the number of components")?;
        let components = c.count(t, "a component count")?;
        let t = c.token("the number of tuples")?;
        let tuples = c.count(t, "a tuple count")?;
        c.token("the data type")?;
        let Some(values) = components.checked_mul(tuples) else {
            return Err(ReadError::Count {
                at: c.at(),
                what: format!("{components} × {tuples} values"),
            });
        };
        for _ in 0..values {
            c.token("a field value")?;
        }
    }
    Ok(())
}

fn type_of(kind: CellKind) -> u32 {
    match (kind, DIM) {
        (CellKind::Simplex, 2) => 5,
        (CellKind::Simplex, _) => 10,
        (CellKind::Cube, 2) => 9,
        (CellKind::Cube, _) => 12,
    }
}

/// Writes `mesh` as a legacy ASCII VTK file (version 3.0, `UNSTRUCTURED_GRID`).
pub fn write(mesh: &Mesh, mut out: impl Write) -> std::io::Result<()> {
    let n = mesh.nodes().len();
    let m = mesh.num_cells();
    let a = mesh.kind().arity();
    writeln!(
        out,
        "{HEADER} 3.0\nsinew mesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {n} float"
    )?;
    for &p in mesh.nodes() {
        let [x, y, z] = xyz(p);
        writeln!(out, "{} {} {}", fmt_real(x), fmt_real(y), fmt_real(z))?;
    }
    writeln!(out, "CELLS {m} {}", m * (a + 1))?;
    for cell in mesh.cells() {
        write!(out, "{a}")?;
        for &i in cell {
            write!(out, " {i}")?;
        }
        writeln!(out)?;
    }
    writeln!(out, "CELL_TYPES {m}")?;
    let ty = type_of(mesh.kind());
    for _ in 0..m {
        writeln!(out, "{ty}")?;
    }
    Ok(())
}

/// [`write()`] into a string.
pub fn to_string(mesh: &Mesh) -> String {
    let mut out = Vec::new();
    // Writing into a Vec cannot fail, and the text is ASCII.
    let _ = write(mesh, &mut out);
    String::from_utf8_lossy(&out).into_owned()
}

// Keeps the voxel reordering honest: bit order and VTK order differ only in corners 2 ↔ 3.
const _: () = assert!(vtk_to_bits(2) == 3 && vtk_to_bits(3) == 2);
