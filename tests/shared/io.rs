//! Mesh files (issue 7): round trips through every writer and reader, the features each
//! reader promises, and one test per kind of bad input, each checking the error variant and
//! that the message names the file and the line.

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::mesh::io::gmsh::GmshVersion;
use crate::dim::mesh::io::{gmsh, tetgen, vtk, ReadError};
use crate::dim::{BuildError, CellKind, Mesh};

/// A small mesh with coordinates that are not round numbers (exact float round trip).
fn mesh(kind: CellKind) -> Mesh {
    let half = Vector::splat(0.37) + Vector::X * 0.123;
    let m = Mesh::cuboid(half, [3; DIM], kind).unwrap();
    let nodes: Vec<Vector> = m
        .nodes()
        .iter()
        .map(|p| *p * 1.1 + Vector::splat(0.01))
        .collect();
    Mesh::new(nodes, m.cell_indices().to_vec(), kind).unwrap()
}

fn same(a: &Mesh, b: &Mesh) {
    assert_eq!(a.kind(), b.kind());
    assert_eq!(a.nodes(), b.nodes());
    assert_eq!(a.cell_indices(), b.cell_indices());
}

/// The error's message names `<memory>` (or the file) and the line.
fn names_line(e: &ReadError, line: usize) {
    let m = e.to_string();
    assert!(
        m.contains(&format!("line {line}")),
        "expected line {line}: {m}"
    );
    assert_eq!(e.location().line, Some(line), "{m}");
}

/// `(x y z)` of a node as written in files (z = 0 in 2D).
fn xyz(p: Vector) -> String {
    let mut c: [Real; 3] = [0.0; 3];
    for d in 0..DIM {
        c[d] = p[d];
    }
    format!("{} {} {}", c[0], c[1], c[2])
}

/// The origin and the unit vectors: one positive simplex.
fn simplex_nodes() -> Vec<Vector> {
    super::support::unit_simplex().nodes().to_vec()
}

const SIMPLEX_GMSH: u32 = if DIM == 2 { 2 } else { 4 };
const FACET_GMSH: u32 = if DIM == 2 { 1 } else { 2 };
const SIMPLEX_VTK: u32 = if DIM == 2 { 5 } else { 10 };
const FACET_VTK: u32 = if DIM == 2 { 3 } else { 5 };

/// Replaces line `n` (1-based) of `text`.
fn replace_line(text: &str, n: usize, with: &str) -> String {
    text.lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == n { with } else { l })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The 1-based number of the first line equal to `line`.
fn line_of(text: &str, line: &str) -> usize {
    text.lines().position(|l| l == line).unwrap() + 1
}

fn first_n_lines(text: &str, n: usize) -> String {
    text.lines().take(n).collect::<Vec<_>>().join("\n")
}

// ---------------------------------------------------------------- round trips

#[test]
fn gmsh_round_trip_both_versions_both_kinds() {
    for kind in [CellKind::Simplex, CellKind::Cube] {
        let m = mesh(kind);
        for version in [GmshVersion::V4_1, GmshVersion::V2_2] {
            let back = gmsh::read_str(&gmsh::to_string(&m, version)).unwrap();
            same(&m, &back);
        }
    }
}

#[test]
fn vtk_round_trip_both_kinds() {
    for kind in [CellKind::Simplex, CellKind::Cube] {
        let m = mesh(kind);
        same(&m, &vtk::read_str(&vtk::to_string(&m)).unwrap());
    }
}

#[test]
fn tetgen_round_trip_simplices_only() {
    let m = mesh(CellKind::Simplex);
    let (node, ele) = tetgen::to_strings(&m).unwrap();
    same(&m, &tetgen::read_str(&node, &ele).unwrap());
    assert!(tetgen::to_strings(&mesh(CellKind::Cube)).is_none());
}

#[test]
fn readers_take_paths_and_readers_and_name_the_file() {
    let dir = std::env::temp_dir().join(format!("sinew-io-{}-{}", std::process::id(), DIM));
    std::fs::create_dir_all(&dir).unwrap();
    let m = mesh(CellKind::Simplex);
    let msh = dir.join("m.msh");
    std::fs::write(&msh, gmsh::to_string(&m, GmshVersion::V4_1)).unwrap();
    same(&m, &gmsh::read(&msh).unwrap());
    let text = vtk::to_string(&m);
    let path = dir.join("m.vtk");
    std::fs::write(&path, &text).unwrap();
    same(&m, &vtk::read(&path).unwrap());
    same(
        &m,
        &vtk::read_from(std::io::BufReader::new(text.as_bytes())).unwrap(),
    );
    let (node, ele) = tetgen::to_strings(&m).unwrap();
    let (pn, pe) = (dir.join("m.node"), dir.join("m.ele"));
    std::fs::write(&pn, &node).unwrap();
    std::fs::write(&pe, &ele).unwrap();
    same(&m, &tetgen::read(&pn, &pe).unwrap());
    same(
        &m,
        &tetgen::read_from(node.as_bytes(), ele.as_bytes()).unwrap(),
    );

    // A broken file: the message names its path and the line.
    std::fs::write(&path, replace_line(&text, 6, "1.0 zz 0")).unwrap();
    let e = vtk::read(&path).unwrap_err();
    assert!(matches!(e, ReadError::Number { .. }), "{e}");
    assert!(e.to_string().contains(&path.display().to_string()), "{e}");
    names_line(&e, 6);
    // A missing file.
    let e = gmsh::read(dir.join("missing.msh")).unwrap_err();
    assert!(matches!(e, ReadError::Io { .. }), "{e}");
    assert!(e.to_string().contains("missing.msh"), "{e}");
    // Memory input is named <memory>; TetGen says which of the two files.
    let e = gmsh::read_str("$MeshFormat\n9.9 0 8\n").unwrap_err();
    assert!(e.to_string().starts_with("<memory>, line 2"), "{e}");
    let e = tetgen::read_str(&node, "1 9 0\n").unwrap_err();
    assert!(e.to_string().starts_with("<memory>.ele, line 1"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------- what readers accept

/// Gmsh 4.1 with sparse node tags over two entity blocks, an unused geometry point, and
/// boundary and point elements that must be skipped.
#[test]
fn gmsh_v41_sparse_tags_blocks_and_lower_dimensional_elements() {
    let nodes = simplex_nodes();
    let n = nodes.len();
    let mut t = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    t += "$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n";
    // Tags 10, 20, ... in two blocks (the second one parametric), plus the unused tag 7.
    t += &format!("$Nodes\n3 {} 7 {}\n", n + 1, 10 * n);
    t += "0 1 0 1\n7\n5 5 0\n";
    t += &format!("{DIM} 1 0 {}\n", n - 1);
    for k in 0..n - 1 {
        t += &format!("{}\n", 10 * (k + 1));
    }
    for p in &nodes[..n - 1] {
        t += &format!("{}\n", xyz(*p));
    }
    let params = ["0.5"; DIM - 1].join(" ");
    t += &format!(
        "{} 2 1 1\n{}\n{} {params}\n",
        DIM - 1,
        10 * n,
        xyz(nodes[n - 1])
    );
    t += "$EndNodes\n";
    let tags: Vec<String> = (1..=n).map(|k| (10 * k).to_string()).collect();
    t += "$Elements\n3 3 1 4\n";
    t += "0 1 15 1\n1 7\n";
    t += &format!("{} 2 {FACET_GMSH} 1\n2 {}\n", DIM - 1, tags[1..].join(" "));
    // The cell listed inverted: it is reoriented. (Listed a second time, upright, it would be
    // a duplicate cell: an error.)
    let mut inverted = tags.clone();
    inverted.swap(0, 1);
    let cells = format!(
        "{DIM} 1 {SIMPLEX_GMSH} 1\n4 {}\n$EndElements\n",
        inverted.join(" ")
    );
    let m = gmsh::read_str(&(t.clone() + &cells)).unwrap();
    assert_eq!(
        m.nodes(),
        &nodes[..],
        "geometry point 7 dropped, order kept"
    );
    assert_eq!(m.num_cells(), 1);
    assert!(m.rest_volumes().iter().all(|v| *v > 0.0));
    assert_eq!(
        m.cell(0),
        &[0, 1, 2, 3][..DIM + 1],
        "inverted cell reordered"
    );
    let twice = format!(
        "{DIM} 1 {SIMPLEX_GMSH} 2\n3 {}\n4 {}\n$EndElements\n",
        tags.join(" "),
        inverted.join(" ")
    );
    let t = t.replace("$Elements\n3 3 1 4\n", "$Elements\n3 4 1 4\n");
    let e = gmsh::read_str(&(t + &twice)).unwrap_err();
    assert!(e.to_string().contains("same vertices as cell 0"), "{e}");
}

#[test]
fn gmsh_v22_tags_and_skipped_elements() {
    let nodes = simplex_nodes();
    let mut t = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nanything $Nodes\n$EndComments\n",
    );
    t += &format!("$Nodes\n{}\n", nodes.len());
    for (k, p) in nodes.iter().enumerate().rev() {
        t += &format!("{} {}\n", 100 + k, xyz(*p));
    }
    t += "$EndNodes\n$Elements\n3\n";
    t += "1 15 2 0 1 100\n";
    t += &format!(
        "2 {FACET_GMSH} 2 0 1 {}\n",
        (101..=100 + DIM)
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    t += &format!(
        "3 {SIMPLEX_GMSH} 3 0 1 5 {}\n",
        (100..=100 + DIM)
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    t += "$EndElements\n$NodeData\n1\n\"u\"\n$EndNodeData\n";
    let m = gmsh::read_str(&t).unwrap();
    assert_eq!(m.num_cells(), 1);
    // Nodes come in file order (reversed here), the cell follows the tags.
    let reversed: Vec<Vector> = nodes.iter().rev().copied().collect();
    assert_eq!(m.nodes(), &reversed[..]);
    assert!((m.total_volume() - m.rest_volumes()[0]).abs() < 1e-9 && m.total_volume() > 0.0);
}

/// TetGen / Triangle: 0-based numbering, attributes, boundary markers, comments.
#[test]
fn tetgen_zero_based_attributes_markers_comments() {
    let nodes = simplex_nodes();
    let mut node = format!("# a comment\n\n{} {DIM} 2 1  # header\n", nodes.len());
    for (k, p) in nodes.iter().enumerate() {
        let c: Vec<String> = (0..DIM).map(|d| p[d].to_string()).collect();
        node += &format!("{k} {} 0.5 -3 1\n", c.join(" "));
    }
    let ids: Vec<String> = (0..=DIM).map(|k| k.to_string()).collect();
    let ele = format!("1 {} 1\n  0 {} 7.5 # region\n", DIM + 1, ids.join(" "));
    let m = tetgen::read_str(&node, &ele).unwrap();
    assert_eq!(m.nodes(), &nodes[..]);
    assert_eq!(m.num_cells(), 1);
}

/// Quadratic cells (10-node tetrahedra, 6-node triangles): corners kept, edge nodes dropped.
#[test]
fn tetgen_quadratic_cells_keep_corners() {
    let corners = simplex_nodes();
    let mut nodes = corners.clone();
    let mut edge_ids = Vec::new();
    for i in 0..=DIM {
        for j in i + 1..=DIM {
            edge_ids.push(nodes.len() + 1);
            nodes.push((corners[i] + corners[j]) * 0.5);
        }
    }
    let mut node = format!("{} {DIM} 0 0\n", nodes.len());
    for (k, p) in nodes.iter().enumerate() {
        let c: Vec<String> = (0..DIM).map(|d| p[d].to_string()).collect();
        node += &format!("{} {}\n", k + 1, c.join(" "));
    }
    let ids: Vec<String> = (1..=DIM + 1)
        .chain(edge_ids)
        .map(|k| k.to_string())
        .collect();
    let ele = format!("1 {} 0\n1 {}\n", ids.len(), ids.join(" "));
    let m = tetgen::read_str(&node, &ele).unwrap();
    assert_eq!(m.nodes(), &corners[..]);
}

/// VTK 5.1's OFFSETS / CONNECTIVITY layout, lower-dimensional cells skipped, point data
/// ignored, points spread over lines freely.
#[test]
fn vtk_51_layout_skipped_cells_and_data() {
    let nodes = simplex_nodes();
    let mut t = String::from("# vtk DataFile Version 5.1\n\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    t += &format!("POINTS {} double\n", nodes.len());
    t += &nodes.iter().map(|p| xyz(*p)).collect::<Vec<_>>().join(" ");
    let simplex: Vec<String> = (0..=DIM).map(|k| k.to_string()).collect();
    t += &format!(
        "\nCELLS 4 {}\nOFFSETS vtktypeint64\n0 1 {} {}\nCONNECTIVITY vtktypeint64\n0\n{}\n{}\n",
        1 + DIM + DIM + 1,
        1 + DIM,
        1 + DIM + DIM + 1,
        simplex[1..].join(" "),
        simplex.join(" ")
    );
    t += &format!("CELL_TYPES 3\n1\n{FACET_VTK}\n{SIMPLEX_VTK}\nPOINT_DATA 4\nSCALARS u float\n");
    let m = vtk::read_str(&t).unwrap();
    assert_eq!(m.num_cells(), 1);
    assert_eq!(m.nodes(), &nodes[..]);
}

/// VTK voxels (pixels in 2D) list corners in bit order: they are reordered to boxes.
#[test]
fn vtk_voxels_are_reordered_to_boxes() {
    let m = mesh(CellKind::Cube);
    let mut t = vtk::to_string(&m);
    // Rewrite each cell in bit order (swap corners 2 ↔ 3 and 6 ↔ 7) and type voxel/pixel.
    let arity = CellKind::Cube.arity();
    let mut out = Vec::new();
    let mut section = "";
    for l in t.lines() {
        if l.starts_with("CELLS") || l.starts_with("CELL_TYPES") {
            section = if l.starts_with("CELLS") {
                "cells"
            } else {
                "types"
            };
            out.push(l.to_owned());
            continue;
        }
        match section {
            "cells" => {
                let mut v: Vec<&str> = l.split(' ').collect();
                for base in (1..=arity).step_by(4) {
                    v.swap(base + 2, base + 3);
                }
                out.push(v.join(" "));
            }
            "types" => out.push(if DIM == 2 { "8" } else { "11" }.to_owned()),
            _ => out.push(l.to_owned()),
        }
    }
    t = out.join("\n");
    same(&m, &vtk::read_str(&t).unwrap());
}

// ---------------------------------------------------------------- bad input

#[test]
fn gmsh_truncated_file() {
    let text = gmsh::to_string(&mesh(CellKind::Simplex), GmshVersion::V2_2);
    let nodes_at = line_of(&text, "$Nodes");
    let cut = first_n_lines(&text, nodes_at + 3);
    let e = gmsh::read_str(&cut).unwrap_err();
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    names_line(&e, nodes_at + 3);
    assert!(e.to_string().contains("ends early"), "{e}");
    // No $Elements at all.
    let cut = first_n_lines(&text, line_of(&text, "$EndNodes"));
    let e = gmsh::read_str(&cut).unwrap_err();
    assert!(
        matches!(e, ReadError::Truncated { ref expected, .. } if expected.contains("$Elements")),
        "{e}"
    );
    names_line(&e, line_of(&text, "$EndNodes"));
    // An unclosed section.
    let e =
        gmsh::read_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 0\n").unwrap_err();
    assert!(
        matches!(e, ReadError::Truncated { ref expected, .. } if expected.contains("$EndEntities")),
        "{e}"
    );
    names_line(&e, 5);
    // Empty input.
    let e = gmsh::read_str("").unwrap_err();
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    names_line(&e, 1);
}

#[test]
fn gmsh_wrong_counts() {
    let m = mesh(CellKind::Simplex);
    let n = m.nodes().len();
    // 2.2: the header declares one node more than listed.
    let text = gmsh::to_string(&m, GmshVersion::V2_2);
    let at = line_of(&text, "$Nodes") + 1;
    let e = gmsh::read_str(&replace_line(&text, at, &(n + 1).to_string())).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, line_of(&text, "$EndNodes"));
    // ... or one fewer.
    let e = gmsh::read_str(&replace_line(&text, at, &(n - 1).to_string())).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, line_of(&text, "$EndNodes") - 1);
    // 4.1: the section header disagrees with its blocks.
    let text = gmsh::to_string(&m, GmshVersion::V4_1);
    let at = line_of(&text, "$Nodes") + 1;
    let e = gmsh::read_str(&replace_line(&text, at, &format!("1 {} 1 {n}", n + 1))).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, at);
    // A cell with one node too many.
    let at = line_of(&text, "$EndElements") - 1;
    let last = text.lines().nth(at - 1).unwrap().to_owned();
    let e = gmsh::read_str(&replace_line(&text, at, &format!("{last} 1"))).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, at);
}

#[test]
fn gmsh_bad_node_tags() {
    let text = gmsh::to_string(&mesh(CellKind::Simplex), GmshVersion::V4_1);
    let at = line_of(&text, "$EndElements") - 1;
    let last = text.lines().nth(at - 1).unwrap();
    let mut v: Vec<&str> = last.split(' ').collect();
    v[1] = "999";
    let e = gmsh::read_str(&replace_line(&text, at, &v.join(" "))).unwrap_err();
    assert!(matches!(e, ReadError::Index { index: 999, .. }), "{e}");
    names_line(&e, at);
    v[1] = "-1";
    let e = gmsh::read_str(&replace_line(&text, at, &v.join(" "))).unwrap_err();
    assert!(matches!(e, ReadError::Number { .. }), "{e}");
    names_line(&e, at);
    // A node tag used twice.
    let first_tag = line_of(&text, "$Nodes") + 3;
    let e = gmsh::read_str(&replace_line(&text, first_tag + 1, "1")).unwrap_err();
    assert!(matches!(e, ReadError::Index { index: 1, .. }), "{e}");
    names_line(&e, first_tag + 1);
}

#[test]
fn gmsh_wrong_version_and_binary() {
    let text = gmsh::to_string(&mesh(CellKind::Simplex), GmshVersion::V4_1);
    for v in ["4 0 8", "4.0 0 8", "3.0 0 8", "x 0 8"] {
        let e = gmsh::read_str(&replace_line(&text, 2, v)).unwrap_err();
        assert!(matches!(e, ReadError::Version { .. }), "{v}: {e}");
        names_line(&e, 2);
    }
    let e = gmsh::read_str(&replace_line(&text, 2, "4.1 1 8")).unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
    assert!(e.to_string().contains("binary"), "{e}");
    let e = gmsh::read_str(&replace_line(&text, 1, "$Nodes")).unwrap_err();
    assert!(matches!(e, ReadError::Syntax { .. }), "{e}");
    names_line(&e, 1);
}

#[test]
fn gmsh_garbage_and_non_finite_numbers() {
    let text = gmsh::to_string(&mesh(CellKind::Simplex), GmshVersion::V2_2);
    let at = line_of(&text, "$Nodes") + 2;
    for (bad, non_finite) in [
        ("1 0.5x 0 0", false),
        ("1 nan 0 0", true),
        ("1 0 1e999 0", true),
        ("1 0 0", false),
    ] {
        let e = gmsh::read_str(&replace_line(&text, at, bad)).unwrap_err();
        if non_finite {
            assert!(matches!(e, ReadError::NonFinite { .. }), "{bad}: {e}");
        } else {
            assert!(
                matches!(e, ReadError::Number { .. } | ReadError::Count { .. }),
                "{bad}: {e}"
            );
        }
        names_line(&e, at);
    }
    // Not UTF-8.
    let mut bytes = text.clone().into_bytes();
    let pos = text.find("$EndNodes").unwrap();
    bytes[pos + 1] = 0xff;
    let e = gmsh::read_from(&bytes[..]).unwrap_err();
    assert!(matches!(e, ReadError::Syntax { .. }), "{e}");
    names_line(&e, line_of(&text, "$EndNodes"));
}

#[test]
fn gmsh_unsupported_elements() {
    let text = gmsh::to_string(&mesh(CellKind::Simplex), GmshVersion::V2_2);
    let at = line_of(&text, "$Elements") + 2;
    // A quadratic simplex of the mesh's dimension, a prism (3D) / quad9 (2D), an unknown type.
    for ty in [
        if DIM == 2 { 9 } else { 11 },
        if DIM == 2 { 10 } else { 6 },
        77,
    ] {
        let e = gmsh::read_str(&replace_line(
            &text,
            at,
            &format!("1 {ty} 0 1 2 3 4 5 6 7 8 9 10"),
        ))
        .unwrap_err();
        assert!(matches!(e, ReadError::Unsupported { .. }), "{ty}: {e}");
        names_line(&e, at);
    }
    // Simplices and boxes mixed.
    let cube_ty = if DIM == 2 { 3 } else { 5 };
    let ids: Vec<String> = (1..=CellKind::Cube.arity())
        .map(|k| k.to_string())
        .collect();
    let e = gmsh::read_str(&replace_line(
        &text,
        at + 1,
        &format!("2 {cube_ty} 0 {}", ids.join(" ")),
    ))
    .unwrap_err();
    assert!(
        matches!(e, ReadError::Unsupported { ref what, .. } if what.contains("one cell kind")),
        "{e}"
    );
    names_line(&e, at + 1);
    // Only boundary elements: no cells.
    let facet: Vec<String> = (1..=DIM).map(|k| k.to_string()).collect();
    let only = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{}\n{}$EndNodes\n$Elements\n1\n1 {FACET_GMSH} 0 {}\n$EndElements\n",
        DIM + 1,
        simplex_nodes().iter().enumerate().map(|(k, p)| format!("{} {}\n", k + 1, xyz(*p))).collect::<String>(),
        facet.join(" ")
    );
    let e = gmsh::read_str(&only).unwrap_err();
    assert!(matches!(e, ReadError::NoCells { .. }), "{e}");
}

#[test]
fn degenerate_cell_is_reported_at_its_line() {
    // Every node on the x axis: the one cell is flat.
    let mut t = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    t += &format!("{}\n", DIM + 1);
    for k in 0..=DIM {
        t += &format!("{} {k} 0 0\n", k + 1);
    }
    let ids: Vec<String> = (1..=DIM + 1).map(|k| k.to_string()).collect();
    t += &format!(
        "$EndNodes\n$Elements\n1\n1 {SIMPLEX_GMSH} 0 {}\n$EndElements\n",
        ids.join(" ")
    );
    let e = gmsh::read_str(&t).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::Mesh {
                source: BuildError::DegenerateElement { cell: 0, .. },
                ..
            }
        ),
        "{e}"
    );
    names_line(&e, line_of(&t, "$EndElements") - 1);
}

#[test]
fn tetgen_bad_input() {
    let m = mesh(CellKind::Simplex);
    let (node, ele) = tetgen::to_strings(&m).unwrap();
    let n = m.nodes().len();
    // Node index out of range (line 3 is the first cell: a comment, the header, then cells).
    let first = ele.lines().nth(2).unwrap();
    let mut v: Vec<&str> = first.split(' ').collect();
    let big = (n + 1).to_string();
    v[1] = &big;
    let e = tetgen::read_str(&node, &replace_line(&ele, 3, &v.join(" "))).unwrap_err();
    assert!(matches!(e, ReadError::Index { .. }), "{e}");
    assert!(e.to_string().starts_with("<memory>.ele, line 3"), "{e}");
    v[1] = "0";
    let e = tetgen::read_str(&node, &replace_line(&ele, 3, &v.join(" "))).unwrap_err();
    assert!(
        matches!(e, ReadError::Index { index: 0, .. }),
        "1-based file: {e}"
    );
    // Wrong dimension in the .node header.
    let other = if DIM == 2 { 3 } else { 2 };
    let e =
        tetgen::read_str(&replace_line(&node, 2, &format!("{n} {other} 0 0")), &ele).unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
    names_line(&e, 2);
    // Header counts: one point too many / too few, a cell line with an extra value.
    let e = tetgen::read_str(
        &replace_line(&node, 2, &format!("{} {DIM} 0 0", n + 1)),
        &ele,
    )
    .unwrap_err();
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    names_line(&e, n + 2);
    let e = tetgen::read_str(
        &replace_line(&node, 2, &format!("{} {DIM} 0 0", n - 1)),
        &ele,
    )
    .unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, n + 2);
    let e = tetgen::read_str(&replace_line(&node, 2, &format!("{n} {DIM} 1 0")), &ele).unwrap_err();
    assert!(
        matches!(e, ReadError::Count { .. }),
        "attribute announced but missing: {e}"
    );
    names_line(&e, 3);
    let e = tetgen::read_str(&node, &replace_line(&ele, 3, &format!("{first} 9"))).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, 3);
    // Points out of sequence.
    let second = node.lines().nth(3).unwrap().replacen("2 ", "5 ", 1);
    let e = tetgen::read_str(&replace_line(&node, 4, &second), &ele).unwrap_err();
    assert!(matches!(e, ReadError::Index { index: 5, .. }), "{e}");
    assert!(e.to_string().starts_with("<memory>.node, line 4"), "{e}");
    // Garbage and truncation.
    let e = tetgen::read_str(&node, &replace_line(&ele, 2, "many 4 0")).unwrap_err();
    assert!(matches!(e, ReadError::Number { .. }), "{e}");
    names_line(&e, 2);
    let e = tetgen::read_str(&node, &first_n_lines(&ele, 4)).unwrap_err();
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    names_line(&e, 4);
    // Nodes per cell that are neither linear nor quadratic.
    let e = tetgen::read_str(
        &node,
        &replace_line(&ele, 2, &format!("{} 5 0", m.num_cells())),
    )
    .unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
}

#[test]
fn vtk_bad_input() {
    let m = mesh(CellKind::Simplex);
    let text = vtk::to_string(&m);
    let n = m.nodes().len();
    let cells = line_of(
        &text,
        &format!("CELLS {} {}", m.num_cells(), m.num_cells() * (DIM + 2)),
    );
    let types = line_of(&text, &format!("CELL_TYPES {}", m.num_cells()));
    // Version, format, dataset.
    let e = vtk::read_str(&replace_line(&text, 1, "# vtk DataFile Version 6.0")).unwrap_err();
    assert!(matches!(e, ReadError::Version { .. }), "{e}");
    names_line(&e, 1);
    let e = vtk::read_str(&replace_line(&text, 1, "# not vtk")).unwrap_err();
    assert!(matches!(e, ReadError::Syntax { .. }), "{e}");
    let e = vtk::read_str(&replace_line(&text, 3, "BINARY")).unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
    names_line(&e, 3);
    let e = vtk::read_str(&replace_line(&text, 4, "DATASET POLYDATA")).unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
    names_line(&e, 4);
    // CELLS size disagrees with the cells.
    let e = vtk::read_str(&replace_line(
        &text,
        cells,
        &format!("CELLS {} {}", m.num_cells(), 7),
    ))
    .unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    // Found at the second cell, the first that does not fit.
    names_line(&e, cells + 2);
    // CELL_TYPES count disagrees with CELLS.
    let e = vtk::read_str(&replace_line(
        &text,
        types,
        &format!("CELL_TYPES {}", m.num_cells() - 1),
    ))
    .unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, types + m.num_cells());
    // An index past the points.
    let ids: Vec<String> = (1..=DIM).map(|k| k.to_string()).collect();
    let bad = format!("{} {} {}", DIM + 1, n + 5, ids.join(" "));
    let e = vtk::read_str(&replace_line(&text, cells + 1, &bad)).unwrap_err();
    assert!(matches!(e, ReadError::Index { .. }), "{e}");
    names_line(&e, cells + 1);
    // POINTS declares more points than it holds.
    let e = vtk::read_str(&replace_line(&text, 5, &format!("POINTS {} float", n + 1))).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, cells);
    // Garbage, truncation, wrong node count in a cell, an unsupported cell type.
    let e = vtk::read_str(&replace_line(&text, 7, "0 0 0x1")).unwrap_err();
    assert!(matches!(e, ReadError::Number { .. }), "{e}");
    names_line(&e, 7);
    let e = vtk::read_str(&first_n_lines(&text, 8)).unwrap_err();
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    names_line(&e, 8);
    let wide: Vec<String> = (0..DIM + 2).map(|k| k.to_string()).collect();
    let size = m.num_cells() * (DIM + 2) + 1;
    let t = replace_line(&text, cells, &format!("CELLS {} {size}", m.num_cells()));
    let t = replace_line(&t, cells + 1, &format!("{} {}", DIM + 2, wide.join(" ")));
    let e = vtk::read_str(&t).unwrap_err();
    assert!(matches!(e, ReadError::Count { .. }), "{e}");
    names_line(&e, cells + 1);
    let e = vtk::read_str(&replace_line(&text, types + 1, "13")).unwrap_err();
    assert!(matches!(e, ReadError::Unsupported { .. }), "{e}");
    names_line(&e, types + 1);
}
