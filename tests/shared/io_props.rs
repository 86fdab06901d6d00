//! Mesh files, properties (issue 7): random valid meshes read back equal from every format;
//! random edits of valid files never panic a reader; every file of the fuzz corpus
//! (`fuzz/corpus/<target>/`) goes through its reader without a panic. The `write_seed_corpus`
//! test (ignored) regenerates the seed part of that corpus.

use std::path::{Path, PathBuf};

use proptest::prelude::*;

use crate::dim::math::{Real, Vector, DIM};
use crate::dim::mesh::io::gmsh::{self, GmshVersion};
use crate::dim::mesh::io::{tetgen, vtk, ReadError};
use crate::dim::{CellKind, Mesh};

/// The three readers, by fuzz target name. TetGen input is `.node`, a NUL byte, `.ele`.
const TARGETS: [&str; 3] = ["gmsh", "tetgen", "vtk"];

fn read(target: &str, bytes: &[u8]) -> Result<Mesh, ReadError> {
    match target {
        "gmsh" => gmsh::read_from(bytes),
        "vtk" => vtk::read_from(bytes),
        _ => {
            let (node, ele) = match bytes.iter().position(|&b| b == 0) {
                Some(i) => (&bytes[..i], &bytes[i + 1..]),
                None => (bytes, &[][..]),
            };
            tetgen::read_from(node, ele)
        }
    }
}

fn write(target: &str, mesh: &Mesh) -> Option<Vec<u8>> {
    match target {
        "gmsh" => Some(gmsh::to_string(mesh, GmshVersion::V4_1).into_bytes()),
        "vtk" => Some(vtk::to_string(mesh).into_bytes()),
        _ => {
            let (node, ele) = tetgen::to_strings(mesh)?;
            Some(format!("{node}\0{ele}").into_bytes())
        }
    }
}

/// Reads `bytes`; a mesh accepted must write and read back unchanged (in every format that
/// can hold it).
fn read_checked(target: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    if let Ok(mesh) = read(target, bytes) {
        for t in TARGETS {
            if let Some(written) = write(t, &mesh) {
                let back =
                    read(t, &written).map_err(|e| TestCaseError::fail(format!("{t}: {e}")))?;
                prop_assert_eq!(back.nodes(), mesh.nodes());
                prop_assert_eq!(back.cell_indices(), mesh.cell_indices());
            }
        }
        let v2 = gmsh::to_string(&mesh, GmshVersion::V2_2);
        let back = gmsh::read_str(&v2).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(back.cell_indices(), mesh.cell_indices());
    }
    Ok(())
}

/// A random mesh: a lattice of random size and kind, its nodes jittered (a fifth of the
/// spacing at most) and scaled, some cells removed.
fn random_mesh(
    res: usize,
    cube: bool,
    scale: Real,
    jitter: &[Real],
    keep: &[bool],
) -> Option<Mesh> {
    let kind = if cube {
        CellKind::Cube
    } else {
        CellKind::Simplex
    };
    let lattice = Mesh::cuboid(Vector::splat(0.5), [res; DIM], kind).ok()?;
    let spacing = 1.0 / (res - 1) as Real;
    let nodes: Vec<Vector> = lattice
        .nodes()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut q = *p;
            for d in 0..DIM {
                q[d] += 0.2 * spacing * jitter.get(i * DIM + d).copied().unwrap_or(0.0);
            }
            q * scale
        })
        .collect();
    let jittered = Mesh::new(nodes, lattice.cell_indices().to_vec(), kind).ok()?;
    let mut k = 0;
    jittered
        .retain_cells(|_| {
            k += 1;
            keep.get(k - 1).copied().unwrap_or(true)
        })
        .ok()
}

/// Tokens that break parsers: signs, overflow, non-finite, section keywords, nothing.
const NASTY: [&str; 14] = [
    "-1",
    "0",
    "1e999",
    "nan",
    "inf",
    "18446744073709551616",
    "4294967296",
    "99999999999999999999999",
    "$EndNodes",
    "$Elements",
    "CELLS",
    "#",
    "",
    "1.5",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_meshes_read_back_equal(
        res in 2usize..5,
        cube in any::<bool>(),
        scale in 0.001f32..1000.0,
        jitter in prop::collection::vec(-1.0f32..1.0, 125 * 3),
        keep in prop::collection::vec(prop::bool::weighted(0.8), 400),
    ) {
        let Some(mesh) = random_mesh(res, cube, scale, &jitter, &keep) else {
            return Err(TestCaseError::reject("not a valid mesh"));
        };
        for t in TARGETS {
            if let Some(bytes) = write(t, &mesh) {
                let back = read(t, &bytes).map_err(|e| TestCaseError::fail(format!("{t}: {e}")))?;
                prop_assert_eq!(back.nodes(), mesh.nodes(), "{}", t);
                prop_assert_eq!(back.cell_indices(), mesh.cell_indices(), "{}", t);
            }
        }
        let back = gmsh::read_str(&gmsh::to_string(&mesh, GmshVersion::V2_2)).unwrap();
        prop_assert_eq!(back.nodes(), mesh.nodes());
        prop_assert_eq!(back.cell_indices(), mesh.cell_indices());
    }

    #[test]
    fn mutated_bytes_never_panic(
        target in 0usize..3,
        cube in any::<bool>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..12),
    ) {
        let kind = if cube { CellKind::Cube } else { CellKind::Simplex };
        let mesh = Mesh::cuboid(Vector::splat(0.5), [3; DIM], kind).unwrap();
        let target = TARGETS[target];
        let Some(mut bytes) = write(target, &mesh) else {
            return Ok(());
        };
        for (at, byte, op) in edits {
            let i = at.index(bytes.len().max(1)).min(bytes.len());
            match op {
                0 if i < bytes.len() => bytes[i] = byte,
                1 => bytes.insert(i, byte),
                _ if i < bytes.len() => {
                    bytes.remove(i);
                }
                _ => {}
            }
        }
        read_checked(target, &bytes)?;
    }

    #[test]
    fn mutated_tokens_never_panic(
        target in 0usize..3,
        cube in any::<bool>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0usize..NASTY.len()), 1..6),
    ) {
        let kind = if cube { CellKind::Cube } else { CellKind::Simplex };
        let mesh = Mesh::cuboid(Vector::splat(0.5), [3; DIM], kind).unwrap();
        let target = TARGETS[target];
        let Some(bytes) = write(target, &mesh) else {
            return Ok(());
        };
        let text = String::from_utf8(bytes).unwrap();
        // Tokens with their separators kept, so that lines stay lines.
        let mut tokens: Vec<String> = text.split(' ').map(str::to_owned).collect();
        for (at, nasty) in edits {
            let i = at.index(tokens.len());
            let t = &tokens[i];
            // Keep a line break that the token carried.
            let tail = t.find('\n').map(|k| t[k..].to_owned()).unwrap_or_default();
            tokens[i] = format!("{}{tail}", NASTY[nasty]);
        }
        read_checked(target, tokens.join(" ").as_bytes())?;
    }
}

fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join("corpus")
        .join(target)
}

/// Every file of the fuzz corpus (seeds and what fuzzing found) goes through its reader
/// without a panic; a mesh accepted writes and reads back unchanged.
#[test]
fn fuzz_corpus_never_panics() {
    for target in TARGETS {
        let mut files: Vec<PathBuf> = std::fs::read_dir(corpus_dir(target))
            .unwrap_or_else(|e| panic!("fuzz/corpus/{target}: {e}"))
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        let (mut ok, mut err) = (0, 0);
        for f in &files {
            let bytes = std::fs::read(f).unwrap();
            match read(target, &bytes) {
                Ok(_) => ok += 1,
                Err(_) => err += 1,
            }
            if let Err(e) = read_checked(target, &bytes) {
                panic!("{}: {e}", f.display());
            }
        }
        println!(
            "{target} ({DIM}D): {} files, {ok} read, {err} refused",
            files.len()
        );
        assert!(
            files.len() >= 8,
            "{target}: only {} corpus files",
            files.len()
        );
    }
}

/// Writes the seed corpus for this dimension: valid files of every kind the reader takes,
/// and the malformed variants of the bad-input tests. Run with
/// `cargo test --test dim3 write_seed_corpus -- --ignored` (and `dim2`).
#[test]
#[ignore]
fn write_seed_corpus() {
    let d = DIM;
    let half = Vector::splat(0.5) + Vector::X * 0.25;
    let simplex = Mesh::cuboid(half, [2; DIM], CellKind::Simplex).unwrap();
    let cube = Mesh::cuboid(Vector::splat(0.5), [2; DIM], CellKind::Cube).unwrap();
    let save = |target: &str, name: &str, bytes: &[u8]| {
        let dir = corpus_dir(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(format!("seed-{d}d-{name}")), bytes).unwrap();
    };
    let truncate = |b: &[u8]| b[..b.len() * 2 / 3].to_vec();
    for (name, m) in [("simplex", &simplex), ("cube", &cube)] {
        for (v, tag) in [(GmshVersion::V4_1, "v41"), (GmshVersion::V2_2, "v22")] {
            let text = gmsh::to_string(m, v);
            save("gmsh", &format!("{name}-{tag}.msh"), text.as_bytes());
            save(
                "gmsh",
                &format!("{name}-{tag}-truncated.msh"),
                &truncate(text.as_bytes()),
            );
            save(
                "gmsh",
                &format!("{name}-{tag}-garbage.msh"),
                text.replacen("0.5", "0.5x", 1).as_bytes(),
            );
        }
        let text = vtk::to_string(m);
        save("vtk", &format!("{name}.vtk"), text.as_bytes());
        save(
            "vtk",
            &format!("{name}-truncated.vtk"),
            &truncate(text.as_bytes()),
        );
        // The first cell's first node past the points.
        let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
        let cells = lines.iter().position(|l| l.starts_with("CELLS")).unwrap();
        let mut first: Vec<&str> = lines[cells + 1].split(' ').collect();
        first[1] = "99";
        lines[cells + 1] = first.join(" ");
        save(
            "vtk",
            &format!("{name}-badindex.vtk"),
            lines.join("\n").as_bytes(),
        );
        save(
            "vtk",
            &format!("{name}-51.vtk"),
            text.replace("Version 3.0", "Version 5.1").as_bytes(),
        );
    }
    let text = gmsh::to_string(&simplex, GmshVersion::V4_1);
    save(
        "gmsh",
        "version40.msh",
        text.replacen("4.1 0 8", "4.0 0 8", 1).as_bytes(),
    );
    save(
        "gmsh",
        "binary.msh",
        text.replacen("4.1 0 8", "4.1 1 8", 1).as_bytes(),
    );
    save("gmsh", "nan.msh", text.replacen("0.5", "nan", 1).as_bytes());
    let text = vtk::to_string(&simplex);
    save(
        "vtk",
        "binary.vtk",
        text.replacen("ASCII", "BINARY", 1).as_bytes(),
    );
    save(
        "vtk",
        "polydata.vtk",
        text.replacen("UNSTRUCTURED_GRID", "POLYDATA", 1).as_bytes(),
    );
    let (node, ele) = tetgen::to_strings(&simplex).unwrap();
    let both = format!("{node}\0{ele}");
    save("tetgen", "simplex.node-ele", both.as_bytes());
    save("tetgen", "truncated.node-ele", &truncate(both.as_bytes()));
    save(
        "tetgen",
        "zero-based.node-ele",
        both.replace("\n1 ", "\n0 ").as_bytes(),
    );
    save(
        "tetgen",
        "comments.node-ele",
        both.replace('\n', "  # note\n").as_bytes(),
    );
    save(
        "tetgen",
        "dimension.node-ele",
        both.replacen(&format!(" {d} 0 0"), " 7 0 0", 1).as_bytes(),
    );
    save(
        "tetgen",
        "garbage.node-ele",
        both.replacen("0.5", "0.5.5", 1).as_bytes(),
    );
    save("tetgen", "no-ele.node-ele", node.as_bytes());
    save(
        "tetgen",
        "counts.node-ele",
        both.replacen(
            &format!("{} {d} 0 0", simplex.nodes().len()),
            &format!("{} {d} 0 0", simplex.nodes().len() + 3),
            1,
        )
        .as_bytes(),
    );
}
