//! Mesh files: readers and writers for [Gmsh `.msh`](gmsh), [TetGen / Triangle
//! `.node` + `.ele`](tetgen) and [legacy VTK `.vtk`](vtk), all ASCII.
//!
//! Each reader takes a path, a `&str` or any [`BufRead`], never panics, and returns either a
//! validated [`Mesh`] or a [`ReadError`] that names the file (its path, or `<memory>` for a
//! string or reader), the line and the reason. The cells taken are those of the mesh's
//! dimension: tetrahedra (or hexahedra) in 3D, triangles (or quads) in 2D. Lower-dimensional
//! elements (boundary triangles, lines, points) are skipped; elements of a higher dimension
//! are an error.
//!
//! What every reader does after parsing, the same for all formats:
//! * **Orientation.** Meshers disagree on the orientation of their cells (and users cannot
//!   choose it), so a cell with a negative signed volume is reordered to a positive one: the
//!   first two vertices of a simplex are swapped; a box is mirrored. Degenerate cells (zero
//!   volume, a repeated vertex) are still an error, reported at the line of the cell.
//! * **Unused nodes** (a Gmsh geometry point such as a circle centre, a TetGen input point
//!   that no tetrahedron uses) are dropped and the others renumbered in file order.
//! * The result goes through [`Mesh::new`]; its [`BuildError`] comes back as
//!   [`ReadError::Mesh`], with the line of the offending cell or node.
//!
//! The parsers are written once and compiled once per dimension (in `sinew::dim2` and
//! `sinew::dim3`) like the rest of the crate: they are small, their output is that
//! dimension's [`Mesh`] and the element types they take depend on the dimension, so a
//! dimension-free intermediate form would only add a conversion step.

/// A one-file format's three entry points (`read`, `read_str`, `read_from`), written once over
/// the format's `parse(text, file)`.
macro_rules! one_file_readers {
    ($ext:literal) => {
        #[doc = concat!("Reads a `", $ext, "` file.")]
        pub fn read(path: impl AsRef<std::path::Path>) -> Result<Mesh, ReadError> {
            let (file, text) = super::load_path(path.as_ref())?;
            parse(&text, &file)
        }

        #[doc = concat!("Reads `", $ext, "` text; errors name the file `<memory>`.")]
        pub fn read_str(text: &str) -> Result<Mesh, ReadError> {
            parse(text, super::MEMORY)
        }

        #[doc = concat!(
                    "Reads `", $ext, "` text from a reader; errors name the file `<memory>`."
                )]
        pub fn read_from(reader: impl std::io::BufRead) -> Result<Mesh, ReadError> {
            let text = super::load_reader(reader, super::MEMORY)?;
            parse(&text, super::MEMORY)
        }
    };
}

pub mod gmsh;
pub mod tetgen;
pub mod vtk;

use std::fmt;
use std::io::BufRead;
use std::path::Path;

use super::super::error::BuildError;
use super::super::math::{self, Real, Vector, DIM, DIM_NAME};
use super::cube::CUBE_ARITY;
use super::{cell_volume, CellKind, Mesh};

/// The name errors give to input that comes from a string or a reader rather than a file.
pub const MEMORY: &str = "<memory>";

/// Where in the input an error was found: the file and, when known, the line (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The path of the file, or [`MEMORY`] for a string or reader input.
    pub file: String,
    /// The 1-based line number, when the error belongs to one line.
    pub line: Option<usize>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}, line {}", self.file, line),
            None => write!(f, "{}", self.file),
        }
    }
}

/// Why a mesh file could not be read. Every variant names the file and (but for
/// [`ReadError::Io`]) the line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The path.
        file: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The input ends before the data it announced.
    #[error("{at}: the file ends early: expected {expected}")]
    Truncated {
        /// The last line read.
        at: Location,
        /// What was still expected.
        expected: String,
    },
    /// A keyword or a section is not the one expected here (or the input is not UTF-8 text).
    #[error("{at}: expected {expected}, found `{found}`")]
    Syntax {
        /// Where.
        at: Location,
        /// What was expected.
        expected: String,
        /// What was found (shortened).
        found: String,
    },
    /// A token that should be a number is not.
    #[error("{at}: `{token}` is not {expected}")]
    Number {
        /// Where.
        at: Location,
        /// The token (shortened).
        token: String,
        /// What kind of number was expected.
        expected: &'static str,
    },
    /// A coordinate is NaN, infinite or too large for the mesh's floating-point type.
    #[error("{at}: non-finite coordinate `{token}`")]
    NonFinite {
        /// Where.
        at: Location,
        /// The token.
        token: String,
    },
    /// A count disagrees with the data: a header announces more or fewer records than there
    /// are, a line holds the wrong number of values.
    #[error("{at}: wrong count: {what}")]
    Count {
        /// Where.
        at: Location,
        /// What disagrees.
        what: String,
    },
    /// A cell refers to a node that does not exist, or a node number is out of sequence.
    #[error("{at}: bad node index {index}: {reason}")]
    Index {
        /// Where.
        at: Location,
        /// The index or tag as written in the file.
        index: u64,
        /// Why it is bad.
        reason: String,
    },
    /// The format version is not one this reader supports.
    #[error("{at}: unsupported version `{found}` (this reader supports {supported})")]
    Version {
        /// Where.
        at: Location,
        /// The version found.
        found: String,
        /// The versions supported.
        supported: &'static str,
    },
    /// Valid in the format, but not supported: binary files, other dataset types, element
    /// types of the mesh's dimension other than linear simplices and boxes, mixed cell kinds.
    #[error("{at}: unsupported: {what}")]
    Unsupported {
        /// Where.
        at: Location,
        /// What.
        what: String,
    },
    /// A 2D read found a point off the x-y plane.
    #[error("{at}: z = {z} is not zero; a 2D read takes meshes in the x-y plane")]
    OutOfPlane {
        /// Where.
        at: Location,
        /// The z coordinate found.
        z: Real,
    },
    /// The file holds no cell of the mesh's dimension.
    #[error("{at}: no {cells} in the file (a {dim} read takes {cells}; lower-dimensional elements are skipped)")]
    NoCells {
        /// The end of the file.
        at: Location,
        /// The cells looked for.
        cells: &'static str,
        /// The dimension.
        dim: &'static str,
    },
    /// The data parsed but does not make a valid mesh; `at.line` is the line of the
    /// offending cell or node when the error names one.
    #[error("{at}: {source}")]
    Mesh {
        /// Where.
        at: Location,
        /// Why the mesh is invalid.
        #[source]
        source: BuildError,
    },
}

impl ReadError {
    /// Where the error was found (for [`ReadError::Io`], the file without a line).
    pub fn location(&self) -> Location {
        match self {
            ReadError::Io { file, .. } => Location {
                file: file.clone(),
                line: None,
            },
            ReadError::Truncated { at, .. }
            | ReadError::Syntax { at, .. }
            | ReadError::Number { at, .. }
            | ReadError::NonFinite { at, .. }
            | ReadError::Count { at, .. }
            | ReadError::Index { at, .. }
            | ReadError::Version { at, .. }
            | ReadError::Unsupported { at, .. }
            | ReadError::OutOfPlane { at, .. }
            | ReadError::NoCells { at, .. }
            | ReadError::Mesh { at, .. } => at.clone(),
        }
    }
}

/// Shortens a token for a message (garbage can be long).
fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    match s.char_indices().nth(MAX) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_owned(),
    }
}

/// Reads a whole file as UTF-8 text.
fn load_path(path: &Path) -> Result<(String, String), ReadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        file: file.clone(),
        source,
    })?;
    let text = decode(bytes, &file)?;
    Ok((file, text))
}

/// Reads a whole reader as UTF-8 text.
fn load_reader(mut reader: impl BufRead, file: &str) -> Result<String, ReadError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|source| ReadError::Io {
            file: file.to_owned(),
            source,
        })?;
    decode(bytes, file)
}

fn decode(bytes: Vec<u8>, file: &str) -> Result<String, ReadError> {
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
        ReadError::Syntax {
            at: Location {
                file: file.to_owned(),
                line: Some(line),
            },
            expected: "UTF-8 text".into(),
            found: format!("the byte 0x{:02x}", bytes.get(valid).copied().unwrap_or(0)),
        }
    })
}

/// A line-and-token cursor over text, with the line numbers errors need.
struct Cursor<'a> {
    file: &'a str,
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    comment: Option<char>,
    /// 1-based number of the current line (0 before the first).
    line: usize,
    /// The rest of the current line.
    tokens: std::iter::Peekable<std::str::SplitWhitespace<'a>>,
}

impl<'a> Cursor<'a> {
    fn new(text: &'a str, file: &'a str, comment: Option<char>) -> Self {
        Cursor {
            file,
            lines: text.lines().enumerate(),
            comment,
            line: 0,
            tokens: "".split_whitespace().peekable(),
        }
    }

    fn at(&self) -> Location {
        self.at_line(self.line.max(1))
    }

    fn at_line(&self, line: usize) -> Location {
        Location {
            file: self.file.to_owned(),
            line: Some(line),
        }
    }

    /// The next line, raw (even when blank); `None` at the end.
    fn raw_line(&mut self) -> Option<&'a str> {
        let (i, l) = self.lines.next()?;
        self.line = i + 1;
        self.tokens = "".split_whitespace().peekable();
        Some(l)
    }

    /// Moves to the next line that holds a token (comments stripped); false at the end.
    fn next_line(&mut self) -> bool {
        for (i, l) in self.lines.by_ref() {
            let l = match self.comment {
                Some(c) => l.split(c).next().unwrap_or(""),
                None => l,
            };
            let mut tokens = l.split_whitespace().peekable();
            if tokens.peek().is_some() {
                self.line = i + 1;
                self.tokens = tokens;
                return true;
            }
        }
        false
    }

    /// Moves to the next non-blank line or fails with [`ReadError::Truncated`].
    fn line(&mut self, expected: &str) -> Result<(), ReadError> {
        if self.next_line() {
            Ok(())
        } else {
            Err(self.truncated(expected))
        }
    }

    /// Moves to the next record line of a section that declared `declared` records: a line
    /// starting with `$` (the section's end) means the count was wrong.
    fn record_line(&mut self, what: &str, index: usize, declared: usize) -> Result<(), ReadError> {
        if !self.next_line() {
            return Err(self.truncated(&format!("{what} {} of {declared}", index + 1)));
        }
        if let Some(&t) = self.tokens.peek() {
            if t.starts_with('$') {
                return Err(ReadError::Count {
                    at: self.at(),
                    what: format!(
                        "`{}` after {index} {what}s, but the header declares {declared}",
                        shorten(t)
                    ),
                });
            }
        }
        Ok(())
    }

    fn truncated(&self, expected: &str) -> ReadError {
        ReadError::Truncated {
            at: self.at(),
            expected: expected.to_owned(),
        }
    }

    /// The next token on the current line, or a [`ReadError::Count`] error if it ended.
    fn field(&mut self, expected: &str) -> Result<&'a str, ReadError> {
        self.field_with(|| expected.to_owned())
    }

    /// [`Cursor::field`], the message built only on failure (hot loops).
    fn field_with(&mut self, expected: impl FnOnce() -> String) -> Result<&'a str, ReadError> {
        match self.tokens.next() {
            Some(t) => Ok(t),
            None => Err(ReadError::Count {
                at: self.at(),
                what: format!("the line ends before {}", expected()),
            }),
        }
    }

    /// The next token, on this line or the next ones.
    fn token(&mut self, expected: &str) -> Result<&'a str, ReadError> {
        self.token_with(|| expected.to_owned())
    }

    /// [`Cursor::token`], the message built only on failure (hot loops).
    fn token_with(&mut self, expected: impl FnOnce() -> String) -> Result<&'a str, ReadError> {
        loop {
            if let Some(t) = self.tokens.next() {
                return Ok(t);
            }
            if !self.next_line() {
                return Err(self.truncated(&expected()));
            }
        }
    }

    /// Fails if the current line holds more tokens.
    fn end_of_line(&mut self, what: &str) -> Result<(), ReadError> {
        self.end_of_line_with(|| what.to_owned())
    }

    /// [`Cursor::end_of_line`], the message built only on failure (hot loops).
    fn end_of_line_with(&mut self, what: impl FnOnce() -> String) -> Result<(), ReadError> {
        match self.tokens.next() {
            None => Ok(()),
            Some(t) => Err(ReadError::Count {
                at: self.at(),
                what: format!("unexpected `{}` after {}", shorten(t), what()),
            }),
        }
    }

    /// The number of tokens left on the current line (consumes them).
    fn rest_count(&mut self) -> usize {
        self.tokens.by_ref().count()
    }

    fn keyword(&mut self, word: &str, expected: &str) -> Result<(), ReadError> {
        let t = self.token(expected)?;
        if t.eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            Err(self.syntax(expected, t))
        }
    }

    fn syntax(&self, expected: &str, found: &str) -> ReadError {
        ReadError::Syntax {
            at: self.at(),
            expected: expected.to_owned(),
            found: shorten(found),
        }
    }

    fn uint(&self, token: &str, expected: &'static str) -> Result<u64, ReadError> {
        token.parse::<u64>().map_err(|_| ReadError::Number {
            at: self.at(),
            token: shorten(token),
            expected,
        })
    }

    fn count(&self, token: &str, expected: &'static str) -> Result<usize, ReadError> {
        let n = self.uint(token, expected)?;
        usize::try_from(n).map_err(|_| ReadError::Count {
            at: self.at(),
            what: format!("{n} is too large for {expected}"),
        })
    }

    fn real(&self, token: &str) -> Result<Real, ReadError> {
        let v = token.parse::<Real>().map_err(|_| ReadError::Number {
            at: self.at(),
            token: shorten(token),
            expected: "a coordinate (decimal number)",
        })?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ReadError::NonFinite {
                at: self.at(),
                token: shorten(token),
            })
        }
    }

    /// A point from its three coordinates as written (2D reads require z = 0).
    fn point(&self, c: [Real; 3]) -> Result<Vector, ReadError> {
        if DIM == 2 && c[2] != 0.0 {
            return Err(ReadError::OutOfPlane {
                at: self.at(),
                z: c[2],
            });
        }
        Ok(math::vector_from_slice(&c[..DIM]))
    }
}

/// Room to reserve for `declared` records: a header can claim anything.
fn reserve(declared: usize) -> usize {
    declared.min(1 << 16)
}

/// Parsed nodes and cells, with the line each came from.
struct Raw {
    file: String,
    nodes: Vec<Vector>,
    node_lines: Vec<usize>,
    cells: Vec<u32>,
    cell_lines: Vec<usize>,
    kind: Option<CellKind>,
    end_line: usize,
}

impl Raw {
    fn new(file: &str) -> Self {
        Raw {
            file: file.to_owned(),
            nodes: Vec::new(),
            node_lines: Vec::new(),
            cells: Vec::new(),
            cell_lines: Vec::new(),
            kind: None,
            end_line: 1,
        }
    }

    fn at(&self, line: Option<usize>) -> Location {
        Location {
            file: self.file.clone(),
            line,
        }
    }

    /// Sets the cell kind of the mesh; a second, different kind is an error.
    fn set_kind(&mut self, kind: CellKind, at: Location) -> Result<(), ReadError> {
        match self.kind {
            None => {
                self.kind = Some(kind);
                Ok(())
            }
            Some(k) if k == kind => Ok(()),
            Some(k) => Err(ReadError::Unsupported {
                at,
                what: format!(
                    "{} cells after {} cells: a mesh holds one cell kind",
                    kind.name(),
                    k.name()
                ),
            }),
        }
    }

    /// Orients, compacts and validates.
    fn finish(mut self) -> Result<Mesh, ReadError> {
        let Some(kind) = self.kind else {
            return Err(ReadError::NoCells {
                at: self.at(Some(self.end_line)),
                cells: if DIM == 2 {
                    "triangles or quads"
                } else {
                    "tetrahedra or hexahedra"
                },
                dim: DIM_NAME,
            });
        };
        let arity = kind.arity();
        let mut pts = Vec::with_capacity(arity);
        for c in self.cells.chunks_exact_mut(arity) {
            pts.clear();
            pts.extend(c.iter().filter_map(|&i| self.nodes.get(i as usize)));
            if pts.len() == arity && cell_volume(kind, &pts) < 0.0 {
                reorient(kind, c);
            }
        }
        // Drop the nodes no cell uses; keep the others in file order.
        let mut used = vec![false; self.nodes.len()];
        for &i in &self.cells {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
        if used.iter().any(|u| !u) {
            let mut remap = vec![u32::MAX; self.nodes.len()];
            for (next, (r, _)) in remap.iter_mut().zip(&used).filter(|(_, u)| **u).enumerate() {
                *r = next as u32;
            }
            let mut k = 0;
            self.nodes.retain(|_| {
                k += 1;
                used[k - 1]
            });
            let mut k = 0;
            self.node_lines.retain(|_| {
                k += 1;
                used[k - 1]
            });
            for i in &mut self.cells {
                if let Some(&r) = remap.get(*i as usize) {
                    *i = r;
                }
            }
        }
        let Raw {
            file,
            nodes,
            node_lines,
            cells,
            cell_lines,
            ..
        } = self;
        Mesh::new(nodes, cells, kind).map_err(|source| {
            let line = match &source {
                BuildError::IndexOutOfRange { cell, .. }
                | BuildError::DegenerateElement { cell, .. }
                | BuildError::InvertedElement { cell, .. } => cell_lines.get(*cell).copied(),
                BuildError::NonFiniteCoordinate { node, .. }
                | BuildError::UnreferencedNode { node } => node_lines.get(*node).copied(),
                _ => None,
            };
            ReadError::Mesh {
                at: Location { file, line },
                source,
            }
        })
    }
}

/// "triangles" / "tetrahedra" for messages.
fn plural(kind: CellKind) -> &'static str {
    match (kind, DIM) {
        (CellKind::Simplex, 2) => "triangles",
        (CellKind::Simplex, _) => "tetrahedra",
        (CellKind::Cube, 2) => "quads",
        (CellKind::Cube, _) => "hexahedra",
    }
}

/// Reverses the orientation of a cell: swaps the first two vertices of a simplex; mirrors a
/// box (VTK order) across its diagonal plane x = y (corners 1 ↔ 3, and 5 ↔ 7 in 3D).
fn reorient(kind: CellKind, c: &mut [u32]) {
    match kind {
        CellKind::Simplex => c.swap(0, 1),
        CellKind::Cube => {
            for base in (0..CUBE_ARITY).step_by(4) {
                c.swap(base + 1, base + 3);
            }
        }
    }
}

/// Writes a real so that it reads back to the same value.
fn fmt_real(v: Real) -> String {
    format!("{v}")
}

/// The three coordinates of a node as written (z = 0 in 2D).
fn xyz(p: Vector) -> [Real; 3] {
    let mut c = [0.0; 3];
    for (d, cd) in c.iter_mut().enumerate().take(DIM) {
        *cd = p[d];
    }
    c
}
