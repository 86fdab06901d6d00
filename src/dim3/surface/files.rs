//! Surface files: every triangle of a file, welded and checked into one [`Surface`].
//!
//! Each format has `read(path)` and `read_bytes(bytes)` (errors name the file `<memory>`).
//! Parsing is the format crate's (`mesh-loader` for STL and OBJ, `gltf`), whose message a
//! [`SurfaceReadError::Parse`] carries; what the file holds is then checked as
//! [`Surface::welded`] checks it, at 10⁻⁶ of the bounding-box diagonal.

use std::path::Path;

use super::super::math::{Real, Vector};
use super::{file_tolerance, Surface, SurfaceError};

/// The name errors give to input that comes from bytes rather than a file.
const MEMORY: &str = "<memory>";

/// Why a surface file could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceReadError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The path.
        file: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The format's parser rejected the file (its message says where).
    #[error("{file}: {message}")]
    Parse {
        /// The path, or `<memory>`.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// The file is well formed but holds something a surface cannot be made of (a glTF
    /// primitive of lines or points, a sparse accessor, a buffer it does not contain).
    #[error("{file}: {what}")]
    Unsupported {
        /// The path, or `<memory>`.
        file: String,
        /// What, and where in the file.
        what: String,
    },
    /// The file holds no triangle.
    #[error("{file}: no triangles")]
    Empty {
        /// The path, or `<memory>`.
        file: String,
    },
    /// The triangles do not make a closed, manifold, consistently oriented surface (the
    /// triangles and vertices numbered in file order, every mesh of the file after the one
    /// before).
    #[error("{file}: {error}")]
    Surface {
        /// The path, or `<memory>`.
        file: String,
        /// What is wrong, naming the triangle, edge or vertex.
        error: SurfaceError,
    },
}

fn load(path: &Path) -> Result<(String, Vec<u8>), SurfaceReadError> {
    let file = path.display().to_string();
    match std::fs::read(path) {
        Ok(bytes) => Ok((file, bytes)),
        Err(source) => Err(SurfaceReadError::Io { file, source }),
    }
}

/// Triangles gathered from a file's meshes, each mesh's indices shifted past the ones before.
#[derive(Default)]
struct Soup {
    vertices: Vec<Vector>,
    triangles: Vec<[u32; 3]>,
}

impl Soup {
    /// Appends a mesh whose triangles index `vertices` from 0.
    fn append(&mut self, vertices: impl IntoIterator<Item = [f32; 3]>, triangles: &[[u32; 3]]) {
        let base = self.vertices.len() as u32;
        self.vertices.extend(
            vertices
                .into_iter()
                .map(|p| Vector::from_array(p.map(Real::from))),
        );
        // An index past this mesh's vertices stays past every vertex, for the check to name.
        self.triangles
            .extend(triangles.iter().map(|t| t.map(|i| i.saturating_add(base))));
    }

    fn finish(self, file: &str) -> Result<Surface, SurfaceReadError> {
        if self.triangles.is_empty() {
            return Err(SurfaceReadError::Empty { file: file.into() });
        }
        let tolerance = file_tolerance(&self.vertices);
        Surface::welded(self.vertices, self.triangles, tolerance).map_err(|error| {
            SurfaceReadError::Surface {
                file: file.into(),
                error,
            }
        })
    }
}

#[cfg(any(feature = "stl", feature = "obj"))]
fn from_scene(
    scene: std::io::Result<mesh_loader::Scene>,
    file: &str,
) -> Result<Surface, SurfaceReadError> {
    let scene = scene.map_err(|e| SurfaceReadError::Parse {
        file: file.into(),
        message: e.to_string(),
    })?;
    let mut soup = Soup::default();
    for mesh in &scene.meshes {
        soup.append(mesh.vertices.iter().copied(), &mesh.faces);
    }
    soup.finish(file)
}

/// STL, binary or ASCII (feature `stl`). Every facet stores its own corners: they are welded.
#[cfg(feature = "stl")]
pub mod stl {
    use super::*;

    /// Reads an STL file.
    pub fn read(path: impl AsRef<Path>) -> Result<Surface, SurfaceReadError> {
        let (file, bytes) = load(path.as_ref())?;
        from_scene(mesh_loader::stl::from_slice(&bytes), &file)
    }

    /// Reads STL bytes; errors name the file `<memory>`.
    pub fn read_bytes(bytes: &[u8]) -> Result<Surface, SurfaceReadError> {
        from_scene(mesh_loader::stl::from_slice(bytes), MEMORY)
    }
}

/// Wavefront OBJ (feature `obj`): every object and group; polygons are split into
/// triangles by the parser; materials are not read.
#[cfg(feature = "obj")]
pub mod obj {
    use super::*;

    fn parse(bytes: &[u8], path: Option<&Path>) -> std::io::Result<mesh_loader::Scene> {
        mesh_loader::obj::from_slice(bytes, path, |_| -> std::io::Result<Vec<u8>> {
            Err(std::io::Error::other("materials are not read"))
        })
    }

    /// Reads an OBJ file.
    pub fn read(path: impl AsRef<Path>) -> Result<Surface, SurfaceReadError> {
        let (file, bytes) = load(path.as_ref())?;
        from_scene(parse(&bytes, Some(path.as_ref())), &file)
    }

    /// Reads OBJ text; errors name the file `<memory>`.
    pub fn read_bytes(bytes: &[u8]) -> Result<Surface, SurfaceReadError> {
        from_scene(parse(bytes, None), MEMORY)
    }
}

/// glTF 2.0 (feature `gltf`): `.glb`, or `.gltf` with its buffers embedded (`data:` URIs)
/// or in files beside it. Every triangle primitive of the default scene (the first scene, or
/// every mesh when there is none), placed by its nodes' transforms.
#[cfg(feature = "gltf")]
pub mod gltf {
    use super::*;
    use ::gltf::mesh::Mode;
    use ::gltf::Gltf;
    use rapier3d::glamx::Mat4;

    /// Reads a `.gltf` or `.glb` file; external buffers are read from beside it.
    pub fn read(path: impl AsRef<Path>) -> Result<Surface, SurfaceReadError> {
        let path = path.as_ref();
        let (file, bytes) = load(path)?;
        parse(&bytes, path.parent(), &file)
    }

    /// Reads glTF or GLB bytes (external buffers are unsupported); errors name the file
    /// `<memory>`.
    pub fn read_bytes(bytes: &[u8]) -> Result<Surface, SurfaceReadError> {
        parse(bytes, None, MEMORY)
    }

    fn parse(bytes: &[u8], dir: Option<&Path>, file: &str) -> Result<Surface, SurfaceReadError> {
        let parse_error = |message: String| SurfaceReadError::Parse {
            file: file.into(),
            message,
        };
        // `gltf` takes the 12-byte header off a GLB's declared length unchecked (an overflow).
        if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)) {
            let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
            if length < 12 {
                return Err(parse_error(format!(
                    "GLB length {length}, shorter than its header"
                )));
            }
        }
        let raw =
            Gltf::from_slice_without_validation(bytes).map_err(|e| parse_error(e.to_string()))?;
        // `gltf`'s validation reads each primitive's POSITION accessor before it checks that
        // accessor's index (an index past the accessors panicked inside it): checked first.
        let json = raw.document.into_json();
        for (m, mesh) in json.meshes.iter().enumerate() {
            for (p, primitive) in mesh.primitives.iter().enumerate() {
                for accessor in primitive.attributes.values() {
                    if accessor.value() >= json.accessors.len() {
                        return Err(parse_error(format!(
                            "mesh {m} primitive {p}: accessor {} of {}",
                            accessor.value(),
                            json.accessors.len()
                        )));
                    }
                }
            }
        }
        let document = ::gltf::Document::from_json(json).map_err(|e| parse_error(e.to_string()))?;
        let gltf = Gltf {
            document,
            blob: raw.blob,
        };
        let unsupported = |what: String| SurfaceReadError::Unsupported {
            file: file.into(),
            what,
        };
        let mut buffers = Vec::new();
        for buffer in gltf.document.buffers() {
            let data = buffer_data(&buffer, gltf.blob.as_deref(), dir).map_err(&unsupported)?;
            if data.len() < buffer.length() {
                return Err(unsupported(format!(
                    "buffer {} holds {} bytes of the {} it declares",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                )));
            }
            buffers.push(data);
        }
        let mut soup = Soup::default();
        let mut add = |mesh: ::gltf::Mesh<'_>, to_world: Mat4| -> Result<(), String> {
            for primitive in mesh.primitives() {
                add_primitive(&mut soup, &buffers, &mesh, &primitive, to_world)?;
            }
            Ok(())
        };
        match gltf
            .document
            .default_scene()
            .or(gltf.document.scenes().next())
        {
            Some(scene) => {
                let mut stack: Vec<_> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
                // Nodes form trees (one parent each); a node met twice is a cycle or a shared
                // child, which the format forbids.
                let mut seen = vec![false; gltf.document.nodes().len()];
                while let Some((node, parent)) = stack.pop() {
                    if std::mem::replace(&mut seen[node.index()], true) {
                        return Err(unsupported(format!(
                            "node {} is reached twice (a cycle, or a node with two parents)",
                            node.index()
                        )));
                    }
                    let to_world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
                    if let Some(mesh) = node.mesh() {
                        add(mesh, to_world).map_err(&unsupported)?;
                    }
                    stack.extend(node.children().map(|c| (c, to_world)));
                }
            }
            None => {
                for mesh in gltf.document.meshes() {
                    add(mesh, Mat4::IDENTITY).map_err(&unsupported)?;
                }
            }
        }
        soup.finish(file)
    }

    /// A buffer's bytes: the GLB's binary chunk, a `data:` URI, or a file beside the glTF.
    fn buffer_data(
        buffer: &::gltf::Buffer<'_>,
        blob: Option<&[u8]>,
        dir: Option<&Path>,
    ) -> Result<Vec<u8>, String> {
        use base64::Engine as _;
        let index = buffer.index();
        match buffer.source() {
            ::gltf::buffer::Source::Bin => blob.map(<[u8]>::to_vec).ok_or(format!(
                "buffer {index} is the binary chunk, which is missing"
            )),
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let data = uri
                    .split_once(";base64,")
                    .map(|(_, data)| data)
                    .ok_or(format!("buffer {index}: a data URI that is not base64"))?;
                base64::engine::general_purpose::STANDARD
                    .decode(data)
                    .map_err(|e| format!("buffer {index}: {e}"))
            }
            ::gltf::buffer::Source::Uri(uri) => match dir {
                Some(dir) => std::fs::read(dir.join(uri))
                    .map_err(|e| format!("buffer {index} (`{uri}`): {e}")),
                None => Err(format!(
                    "buffer {index} is the external file `{uri}`: read the glTF from its path"
                )),
            },
        }
    }

    /// Whether `accessor` lies within its view and the view within its buffer's `data`, its
    /// stride holds an element (the `gltf` reader assumes both), and it is not sparse.
    fn accessor_fits(accessor: &::gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> bool {
        let Some(view) = accessor.view() else {
            return false;
        };
        let count = accessor.count();
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return false;
        }
        let end = count
            .checked_sub(1)
            .and_then(|c| c.checked_mul(stride))
            .and_then(|x| x.checked_add(size))
            .and_then(|x| x.checked_add(accessor.offset()));
        let view_end = view.offset().checked_add(view.length());
        let data = buffers.get(view.buffer().index()).map_or(0, Vec::len);
        accessor.sparse().is_none()
            && matches!(end, Some(end) if end <= view.length())
            && matches!(view_end, Some(e) if e <= data)
    }

    fn add_primitive(
        soup: &mut Soup,
        buffers: &[Vec<u8>],
        mesh: &::gltf::Mesh<'_>,
        primitive: &::gltf::Primitive<'_>,
        to_world: Mat4,
    ) -> Result<(), String> {
        let at = format!("mesh {} primitive {}", mesh.index(), primitive.index());
        if primitive.mode() != Mode::Triangles {
            return Err(format!("{at} is {:?}, not triangles", primitive.mode()));
        }
        let position = primitive
            .get(&::gltf::Semantic::Positions)
            .ok_or(format!("{at} has no positions"))?;
        // The reader takes positions as three `f32`s and indices as unsigned scalars.
        use ::gltf::accessor::{DataType, Dimensions};
        let typed = position.dimensions() == Dimensions::Vec3
            && position.data_type() == DataType::F32
            && primitive.indices().is_none_or(|i| {
                i.dimensions() == Dimensions::Scalar
                    && matches!(i.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
            });
        if !typed {
            return Err(format!(
                "{at}: positions not three floats or indices not unsigned integers"
            ));
        }
        let fits = std::iter::once(&position)
            .chain(primitive.indices().as_ref())
            .all(|a| accessor_fits(a, buffers));
        if !fits {
            return Err(format!(
                "{at}: an accessor is sparse or runs past its buffer"
            ));
        }
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or(format!("{at}: positions unreadable"))?
            .map(|p| to_world.transform_point3(p.into()).into())
            .collect();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(indices) => indices.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{at}: {} indices, not whole triangles",
                indices.len()
            ));
        }
        // A mirroring transform turns the winding over; turn it back.
        let mirrored = to_world.determinant() < 0.0;
        let triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|c| {
                if mirrored {
                    [c[0], c[2], c[1]]
                } else {
                    [c[0], c[1], c[2]]
                }
            })
            .collect();
        soup.append(positions, &triangles);
        Ok(())
    }
}
