//! The library's one error type.
//!
//! Every fallible operation in `chisel` returns [`Result<T>`]. File readers
//! report *where* (file + [`Position`]) and *what was expected*; GPU failures
//! (no adapter, device loss, out-of-memory, validation) are values, never
//! panics.

use std::fmt;
use std::path::PathBuf;

/// A place inside an input file, for error messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Position {
    /// 1-based line number of a text file or text header.
    Line(usize),
    /// 1-based line and column (in characters) of a text file.
    LineColumn(usize, usize),
    /// 0-based byte offset into a (binary) file.
    Byte(u64),
    /// A named header field (e.g. `sizes` of an NRRD header).
    Field(String),
    /// The file as a whole (e.g. its length).
    Whole,
    /// An element of an in-memory structure: `vertex 7`, `triangle 3`,
    /// `shell 2`, `integer 17` of a cell list.
    Item { kind: &'static str, index: u64 },
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Line(n) => write!(f, "line {n}"),
            Position::LineColumn(n, c) => write!(f, "line {n}, column {c}"),
            Position::Byte(n) => write!(f, "byte {n}"),
            Position::Field(k) => write!(f, "field `{k}`"),
            Position::Whole => write!(f, "whole file"),
            Position::Item { kind, index } => write!(f, "{kind} {index}"),
        }
    }
}

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O error on `path`.
    /// (The OS error is part of the message, not a `source`, so that a
    /// printed error chain names it once.)
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    /// Malformed input: `path` at `at`, with what was expected and what was found.
    #[error("{path}: {at}: expected {expected}, found {found}")]
    Format {
        path: PathBuf,
        at: Position,
        expected: String,
        found: String,
    },
    /// A header announces more data than the file holds or the memory budget allows.
    #[error("{path}: {at}: {what} needs {needed} bytes but {limit_kind} is {limit} bytes")]
    Size {
        path: PathBuf,
        at: Position,
        what: String,
        needed: u64,
        limit_kind: &'static str,
        limit: u64,
    },
    /// The file's format is not one chisel reads or writes.
    #[error("{path}: unsupported format: {what}")]
    Unsupported { path: PathBuf, what: String },
    /// A parameter outside its documented range: `name` (as the API or the
    /// command line spells it), the `value` given and the `rule` it breaks.
    #[error("{name} = {value}: {rule}")]
    InvalidParameter {
        name: String,
        value: String,
        rule: String,
    },
    /// A count or size past what a structure, a numbering or an adapter
    /// supports: `what` is counted, `asked` is the count, `allowed` the most.
    #[error("{what}: {asked} exceeds the limit of {allowed}")]
    Limit {
        what: String,
        asked: u64,
        allowed: u64,
    },
    /// Arguments that do not fit together: `what` has `found` items where
    /// `expected` are needed (one per vertex, one per free node, …).
    #[error("{what}: {found} given where {expected} are needed")]
    Mismatch {
        what: String,
        expected: u64,
        found: u64,
    },
    /// An input that must hold at least one item holds none (a mesh with no
    /// triangles, a plan with no steps, no views to render).
    #[error("{what}: none given, at least one is needed")]
    Empty { what: String },
    /// In-memory data that breaks a structural rule: `what` names the
    /// structure (a mesh, a cell list, a spring network), `at` the element,
    /// `problem` the rule it breaks.
    #[error("{what}: {at}: {problem}")]
    InvalidData {
        what: String,
        at: Position,
        problem: String,
    },
    /// A name that is none of the known ones (a view, a solver, a fragment).
    #[error("unknown {kind} `{name}`; known: [{}]", known.join(", "))]
    Unknown {
        kind: &'static str,
        name: String,
        known: Vec<String>,
    },
    /// Valid input whose geometry an algorithm refuses, with where.
    #[error(transparent)]
    Refused(#[from] Refusal),
    /// A broken internal invariant: a bug in chisel, never the input's fault.
    /// The caller stopped the operation (its progress callback said so,
    /// or Ctrl-C in Python).
    #[error("{what}: stopped by the caller")]
    Cancelled { what: String },
    #[error("internal error (a bug in chisel, please report it): {0}")]
    Internal(String),
    /// An error inside one part of a larger input: `context` says which
    /// (a plan step, a cut, a region); [`Error::root`] looks through it.
    #[error("{context}: {inner}")]
    In { context: String, inner: Box<Error> },
    /// No GPU adapter matched the request.
    #[error(
        "no GPU adapter matches `{requested}`; found: [{}]. {hint}",
        available.join("; ")
    )]
    NoAdapter {
        requested: String,
        available: Vec<String>,
        hint: &'static str,
    },
    /// The device could not be created (limits or features refused).
    #[error("could not open device on `{adapter}`: {message}")]
    RequestDevice { adapter: String, message: String },
    /// The device was lost (driver reset, crash, timeout).
    #[error("GPU device lost: {0}")]
    DeviceLost(String),
    /// An output path that names an input of the same command (the same
    /// path, or the same file through a link): refused before anything is
    /// written, so inputs are never overwritten.
    #[error(
        "{output}: is the input {input} (the same file); outputs never overwrite inputs, \
         choose another path"
    )]
    OutputIsInput { output: PathBuf, input: PathBuf },
    /// A host allocation of `bytes` for `what` failed (too large for this machine).
    #[error("not enough memory: {what} needs {bytes} bytes")]
    HostMemory { what: String, bytes: u64 },
    /// An allocation on the device failed: `label` names the buffer or
    /// scope, `message` is the driver's.
    #[error("GPU out of memory in `{label}`: {message}")]
    OutOfMemory { label: String, message: String },
    /// A WGSL kernel or shader failed to parse, validate or build a pipeline.
    #[error("kernel `{name}`: {message}")]
    Kernel { name: String, message: String },
    /// wgpu validation failed outside pipeline creation (bind groups, dispatch).
    #[error("GPU validation error in `{label}`: {message}")]
    Validation { label: String, message: String },
    /// Mapping a buffer for readback failed.
    #[error("readback of `{label}` failed: {message}")]
    Readback { label: String, message: String },
}

/// Geometry an algorithm refuses: the input is well formed but degenerate
/// or outside what the method handles, and the variant says where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// Some patches of a mesh cannot be oriented consistently.
    #[error(
        "{patches} patch(es) of the mesh are non-orientable (like a Möbius strip), the first \
         one contains triangle {triangle}; no triangle was flipped"
    )]
    NonOrientable { patches: usize, triangle: u32 },
    /// A knife triangle touches a surface triangle without crossing it
    /// cleanly (a vertex on the other surface, an edge through an edge,
    /// coplanar triangles).
    #[error(
        "knife triangle {knife_triangle} touches surface triangle {surface_triangle} without \
         crossing it cleanly (a vertex on the other surface, an edge through an edge, or \
         coplanar triangles); move or tilt the knife slightly"
    )]
    KnifeContact {
        knife_triangle: u32,
        surface_triangle: u32,
    },
    /// The cut curve cannot split a triangle (`triangle` names the mesh and
    /// the id): two cut points at one spot, or the curve ends inside.
    #[error("triangulated knife: {triangle} {problem}")]
    CutCurve {
        triangle: String,
        problem: &'static str,
    },
    /// A knife that is not a consistently oriented manifold.
    #[error(
        "knife mesh triangle {triangle}: edge {from}->{to} is degenerate or used twice in one \
         direction; the knife must be a consistently oriented manifold"
    )]
    KnifeNotManifold { triangle: u32, from: u32, to: u32 },
    /// No pole of the sphere lies outside the cap regions, so the cap
    /// cannot be projected to a plane.
    #[error(
        "cap: found no projection pole of the sphere outside the cap regions; move the sphere slightly"
    )]
    NoCapPole,
    /// Hull candidates on one line: no polygon, no polyhedron.
    #[error(
        "the {points} hull candidates are collinear: no polygon or polyhedron (a line of voxels \
         has a hull through its cell corners: `--vertices corners`)"
    )]
    Collinear { points: usize },
    /// A flat hull or object has no inside.
    #[error("{what} is flat: it has no inside")]
    Flat { what: &'static str },
    /// Sibling shells of a polyhedron are not proven separated (disjoint
    /// interiors, no common face area).
    #[error(
        "the merged surface needs sibling shells with disjoint interiors and no common face area"
    )]
    SiblingsNotSeparated,
    /// The face chain of a (malformed) shell tree does not bound a region.
    #[error("merged surface: the face chain does not bound a region: {0}")]
    NotARegion(String),
    /// An iso level at which the volume has no surface.
    #[error("the volume has no surface at the {layer} level {level} (no sample on both sides)")]
    NoSurface { layer: &'static str, level: f64 },
    /// A selection (of bone vertices, of a bone piece) that selects nothing.
    #[error("{what}: empty selection: {detail}")]
    EmptySelection { what: String, detail: String },
    /// Parameter triangles that stay degenerate or flipped after the
    /// repair of isolated ones (DMS parametrisation).
    #[error(
        "the parametrisation folds {} triangle(s) (first: {:?}); isolated ones are repaired, \
         these are not: try another projection",
        triangles.len(),
        &triangles[..triangles.len().min(10)]
    )]
    FoldedParameters { triangles: Vec<u32> },
    /// Two boundary edges of the parameter mesh cross: the parameter
    /// triangles overlap (DMS parametrisation).
    #[error("the parameter domain's boundary crosses itself: edges {edges:?} meet")]
    OverlappingParameters { edges: [[u32; 2]; 2] },
    /// No knot candidate of a vertex lies in its allowed region (inside its
    /// star, or outside the boundary edges at it): the star is too thin.
    #[error(
        "no position for the knot cloud of parameter vertex {vertex}: its star is too thin \
         for the candidate circle"
    )]
    NoKnotPosition { vertex: u32 },
    /// An iterative solver stopped before its tolerance.
    #[error(
        "{what} did not converge: relative residual {residual:e} after {iterations} iterations"
    )]
    NoConvergence {
        what: &'static str,
        iterations: u32,
        residual: f64,
    },
    /// Rays from the fusion centre that do not cross a mesh exactly once:
    /// the mesh is not star-shaped about the centre (or the centre is
    /// outside it, or the mesh is open there).
    #[error(
        "mesh {mesh} is not star-shaped about H = ({:.6}, {:.6}, {:.6}): {failing} of {rays} rays \
         from H cross its surface other than once ({}); choose another --center, or fuse \
         closed meshes that are star-shaped about a common point",
        center[0], center[1], center[2],
        rays_text(examples)
    )]
    NotStarShaped {
        mesh: &'static str,
        center: [f64; 3],
        failing: usize,
        rays: usize,
        /// The first failing rays: unit direction and hit count.
        examples: Vec<([f32; 3], u32)>,
    },
    /// Rays from the fusion centre that cross a mesh an even number of
    /// times: the centre is outside it, or the mesh is open there.
    #[error(
        "mesh {mesh} is not closed around H = ({:.6}, {:.6}, {:.6}): {failing} of {rays} rays \
         from H cross its surface an even number of times ({}); H lies outside it, or it is open \
         there",
        center[0], center[1], center[2],
        rays_text(examples)
    )]
    OpenAlongRays {
        mesh: &'static str,
        center: [f64; 3],
        failing: usize,
        rays: usize,
        /// The first failing rays: unit direction and hit count.
        examples: Vec<([f32; 3], u32)>,
    },
    /// A ∩ B falls into several pieces, where fusing a mesh that is not
    /// star-shaped needs one (seed 001 §2.6.2).
    #[error(
        "fusing a mesh that is not star-shaped about H needs one connected A ∩ B (seed 001 \
         §2.6.2): on a grid of cell {cell:.3e} it has {components} pieces ({points:?} grid \
         points, largest first)"
    )]
    IntersectionNotConnected {
        components: usize,
        /// Grid points of the largest pieces.
        points: Vec<usize>,
        cell: f64,
    },
    /// Subtraction where B reaches out of A along some rays (ρ_B ≥ ρ_A).
    #[error(
        "subtraction needs B inside A along every ray from H (ρ_B < ρ_A): in {failing} of {rays} \
         directions B reaches A's surface or beyond (first: {})",
        directions_text(examples)
    )]
    SubtractionReachesOut {
        failing: usize,
        rays: usize,
        /// The first failing rays' unit directions.
        examples: Vec<[f32; 3]>,
    },
    /// No point was found in A ∩ B from which both meshes are star-shaped.
    #[error("no fusion centre found: {0}; give one with --center")]
    NoStarCenter(String),
    /// A spring network with no springs on free nodes and no damping: no
    /// time step is stable.
    #[error(
        "the network has neither springs on free nodes nor damping: no stable Δt exists; give --dt"
    )]
    NoStableStep,
}

/// "first: direction (x, y, z) with k hits, …" for a refusal's examples.
fn rays_text(examples: &[([f32; 3], u32)]) -> String {
    let list: Vec<String> = examples
        .iter()
        .map(|(d, n)| format!("({:.4}, {:.4}, {:.4}) with {n} hit(s)", d[0], d[1], d[2]))
        .collect();
    format!("first: {}", list.join(", "))
}

/// "(x, y, z), …" for a refusal's example directions.
fn directions_text(examples: &[[f32; 3]]) -> String {
    let list: Vec<String> = examples
        .iter()
        .map(|d| format!("({:.4}, {:.4}, {:.4})", d[0], d[1], d[2]))
        .collect();
    list.join(", ")
}

/// Library result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::Format`].
    pub fn format(
        path: impl Into<PathBuf>,
        at: Position,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        Error::Format {
            path: path.into(),
            at,
            expected: expected.into(),
            found: found.into(),
        }
    }

    /// Shorthand for [`Error::InvalidParameter`].
    pub fn param(
        name: impl Into<String>,
        value: impl fmt::Display,
        rule: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            value: value.to_string(),
            rule: rule.into(),
        }
    }

    /// Shorthand for [`Error::Limit`].
    pub fn limit(
        what: impl Into<String>,
        asked: impl TryInto<u64>,
        allowed: impl TryInto<u64>,
    ) -> Self {
        Error::Limit {
            what: what.into(),
            asked: asked.try_into().unwrap_or(u64::MAX),
            allowed: allowed.try_into().unwrap_or(u64::MAX),
        }
    }

    /// Shorthand for [`Error::Mismatch`].
    pub fn mismatch(what: impl Into<String>, expected: usize, found: usize) -> Self {
        Error::Mismatch {
            what: what.into(),
            expected: expected as u64,
            found: found as u64,
        }
    }

    /// Shorthand for [`Error::Empty`].
    pub fn empty(what: impl Into<String>) -> Self {
        Error::Empty { what: what.into() }
    }

    /// Shorthand for [`Error::InvalidData`] at element `index` of `kind`.
    pub fn data(
        what: impl Into<String>,
        kind: &'static str,
        index: impl TryInto<u64>,
        problem: impl Into<String>,
    ) -> Self {
        Error::InvalidData {
            what: what.into(),
            at: Position::Item {
                kind,
                index: index.try_into().unwrap_or(u64::MAX),
            },
            problem: problem.into(),
        }
    }

    /// Shorthand for [`Error::Unknown`].
    pub fn unknown<S: ToString>(
        kind: &'static str,
        name: impl Into<String>,
        known: impl IntoIterator<Item = S>,
    ) -> Self {
        Error::Unknown {
            kind,
            name: name.into(),
            known: known.into_iter().map(|k| k.to_string()).collect(),
        }
    }

    /// Wraps `self` in the `context` of a larger input ([`Error::In`]).
    pub fn within(self, context: impl Into<String>) -> Self {
        Error::In {
            context: context.into(),
            inner: Box::new(self),
        }
    }

    /// The error itself, looking through [`Error::In`] contexts.
    pub fn root(&self) -> &Error {
        match self {
            Error::In { inner, .. } => inner.root(),
            e => e,
        }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error,
        }
    }
}
