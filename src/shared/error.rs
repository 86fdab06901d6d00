//! Typed errors for everything a user can feed in.

use super::math::Real;

/// Why a mesh, a material or a deformable could not be built.
///
/// Every variant names what was wrong and where (node, cell, parameter), so that the message
/// alone is enough to find the bad datum in the user's input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// The mesh has no node or no cell.
    #[error("empty mesh: {nodes} nodes and {cells} cells; a deformable needs at least one cell")]
    EmptyMesh {
        /// Number of nodes given.
        nodes: usize,
        /// Number of cells given.
        cells: usize,
    },
    /// The flat cell index list is not a whole number of cells.
    #[error("malformed cell list: {len} indices is not a multiple of {arity} (vertices per {kind} cell)")]
    MalformedCells {
        /// Length of the flat index list.
        len: usize,
        /// Vertices per cell.
        arity: usize,
        /// Cell kind name.
        kind: &'static str,
    },
    /// A cell refers to a node that does not exist.
    #[error("cell {cell} refers to node {index}, but the mesh has only {node_count} nodes")]
    IndexOutOfRange {
        /// The offending cell.
        cell: usize,
        /// The index found in it.
        index: u32,
        /// Number of nodes in the mesh.
        node_count: usize,
    },
    /// A node coordinate is NaN or infinite.
    #[error("node {node} has a non-finite coordinate {coordinates:?}")]
    NonFiniteCoordinate {
        /// The offending node.
        node: usize,
        /// Its coordinates.
        coordinates: Vec<Real>,
    },
    /// A rest cell has (nearly) zero volume, or uses one node twice.
    #[error("cell {cell} is degenerate at rest: signed volume {volume:e} (it must be positive and not vanishingly small)")]
    DegenerateElement {
        /// The offending cell.
        cell: usize,
        /// Its signed rest volume (area in 2D); for hexahedra/quads the smallest corner volume.
        volume: Real,
    },
    /// A rest cell is inverted (negative orientation).
    #[error("cell {cell} is inverted at rest: signed volume {volume:e}; reorder its vertices (positive orientation)")]
    InvertedElement {
        /// The offending cell.
        cell: usize,
        /// Its signed rest volume (area in 2D); for hexahedra/quads the smallest corner volume.
        volume: Real,
    },
    /// A per-node list (positions, velocities) of the wrong length.
    #[error("{what}: got {got} values, but the deformable has {expected} nodes")]
    WrongLength {
        /// Which list.
        what: &'static str,
        /// Its length.
        got: usize,
        /// Number of nodes.
        expected: usize,
    },
    /// Two cells have the same vertices.
    #[error("cell {cell} has the same vertices as cell {first}")]
    DuplicateCell {
        /// The later cell.
        cell: usize,
        /// The earlier one.
        first: usize,
    },
    /// A face is shared by more than two cells: cells overlap (or a mesh was concatenated
    /// with itself).
    #[error("the face with nodes {face:?} belongs to {cells} cells; a face belongs to at most two (cells overlap)")]
    OverlappingCells {
        /// The face's nodes.
        face: Vec<u32>,
        /// How many cells share it.
        cells: usize,
    },
    /// A mesh warning ([`MeshWarning`]) turned into an error by
    /// `DeformableBuilder::deny_warnings`.
    #[error("mesh warning denied: {0}")]
    MeshWarning(MeshWarning),
    /// The material is so stiff for its mass that one step needs more substeps than the
    /// pipeline allows (`PipelineSettings::max_substeps`).
    #[error("too stiff for the step: a step of {dt} s needs {substeps:.0} substeps at rest (stable substep {substep:e} s), more than the {max_substeps} allowed; lower the stiffness, raise the mass or shorten the step")]
    TooStiff {
        /// Substeps one step needs at rest.
        substeps: f64,
        /// The largest stable substep at rest, s.
        substep: Real,
        /// The step, s.
        dt: Real,
        /// The pipeline's cap.
        max_substeps: usize,
    },
    /// A node belongs to no cell, so it would have no mass.
    #[error("node {node} belongs to no cell (it would have no mass)")]
    UnreferencedNode {
        /// The offending node.
        node: usize,
    },
    /// The density is zero, negative or not finite.
    #[error("density must be positive and finite, got {density}")]
    NonPositiveDensity {
        /// The value given.
        density: Real,
    },
    /// A stiffness (Young's modulus, raw `k` or `k/m`) is negative or not finite.
    #[error("{what} must be non-negative and finite, got {value}")]
    NegativeStiffness {
        /// Which stiffness parameter.
        what: &'static str,
        /// The value given.
        value: Real,
    },
    /// Another parameter is out of its range.
    #[error("parameter `{name}` = {value} is out of range: expected {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: Real,
        /// The accepted range, in words.
        expected: &'static str,
    },
    /// Plastic flow was asked of a model or cell kind that has none.
    #[error(
        "the {model} model has no plastic flow on {kind} cells: plastic flow needs simplex cells"
    )]
    NoPlasticity {
        /// Model name.
        model: &'static str,
        /// Cell kind name.
        kind: &'static str,
    },
    /// A gas chamber's facets name a node the mesh does not have.
    #[error("chamber {chamber}'s facet {facet} refers to node {index}, but the mesh has only {node_count} nodes")]
    ChamberIndexOutOfRange {
        /// The chamber (in the order the builder was given them).
        chamber: usize,
        /// The offending facet.
        facet: usize,
        /// The index found in it.
        index: u32,
        /// Number of nodes in the mesh.
        node_count: usize,
    },
    /// A gas chamber's facet joins nodes that share no cell: a chamber's facets must lie in
    /// the mesh's cells (a boundary facet, or a face or diagonal inside a cell).
    #[error("chamber {chamber}'s facet {facet} joins nodes that share no cell; a chamber's facets must lie in the mesh's cells")]
    ChamberFacetOutsideCells {
        /// The chamber (in the order the builder was given them).
        chamber: usize,
        /// The offending facet.
        facet: usize,
    },
    /// A gas chamber's facets do not close: a ridge (an edge in 3D, a node in 2D) is not met
    /// once each way by its facets, so the gas would leak there.
    #[error("chamber {chamber} is open at nodes {ridge:?}: its facets must close, each ridge met once each way")]
    OpenChamber {
        /// The chamber (in the order the builder was given them).
        chamber: usize,
        /// The ridge's nodes (two in 3D, one in 2D).
        ridge: Vec<u32>,
    },
    /// A gas chamber's facets enclose no volume at rest, or face into the gas (their normals
    /// must point out of it, into the walls).
    #[error("chamber {chamber} encloses a volume of {volume:e} at rest: its facets must face out of the gas and enclose a positive volume")]
    InvertedChamber {
        /// The chamber (in the order the builder was given them).
        chamber: usize,
        /// The signed volume its facets enclose at rest.
        volume: Real,
    },
    /// A tearing body's tear strain is at or below its plastic yield strain: it would tear
    /// before it flows.
    #[error("tear strain {tear} is at or below the yield strain {yield_strain}: a body must yield before it tears")]
    TearBelowYield {
        /// The tear strain asked.
        tear: Real,
        /// The plastic flow's yield strain.
        yield_strain: Real,
    },
    /// Tearing was asked of a body with gas chambers: a crack would open a chamber.
    #[error("a body with gas chambers cannot tear (a crack would open a chamber)")]
    TearingWithGas,
    /// The element model cannot be built on this cell kind.
    #[error("the {model} model needs simplex cells (triangles / tetrahedra), but the mesh has {kind} cells; build the lattice with CellKind::Simplex")]
    UnsupportedCells {
        /// Model name.
        model: &'static str,
        /// Cell kind name.
        kind: &'static str,
    },
}

/// Something legal in a mesh that is probably a mistake. [`Mesh::diagnose`](super::Mesh::diagnose) lists them;
/// [`DeformableBuilder`](super::DeformableBuilder)'s `deny_warnings` turns them into errors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshWarning {
    /// Two nodes at the same place (within `1e-6` of the mesh's size). Cells that use one or
    /// the other are not connected there: the mesh is cut, and with no self-contact the two
    /// sides can pass through each other. [`Mesh::merge_coincident_nodes`](super::Mesh::merge_coincident_nodes) welds them.
    #[error("nodes {first} and {second} coincide ({distance:e} apart): the mesh is cut there; Mesh::merge_coincident_nodes welds them")]
    CoincidentNodes {
        /// The lower index.
        first: u32,
        /// The higher index.
        second: u32,
        /// Their distance.
        distance: Real,
    },
    /// A surface ridge (an edge in 3D, a node in 2D) shared by other than two boundary facets:
    /// two parts touch along it only, and a contact normal there is ambiguous.
    #[error("the surface is not manifold at nodes {nodes:?}: {facets} boundary facets meet there, not 2")]
    NonManifoldSurface {
        /// The ridge's nodes (two in 3D, one in 2D).
        nodes: Vec<u32>,
        /// Boundary facets that share it.
        facets: usize,
    },
    /// The cells form several pieces that share no node: they move independently.
    #[error("the mesh is in {pieces} pieces that share no node (they move as separate bodies)")]
    Disconnected {
        /// Number of pieces.
        pieces: usize,
    },
}
