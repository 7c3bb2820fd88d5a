//! Mesh topology. PLACEHOLDER — replaced by the topology work.

/// Orientation of a mesh's triangles relative to the enclosed side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    Outward,
    Inward,
    Mixed,
    Undetermined,
}

/// Topological figures of a mesh.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Topology {
    pub orientation: Orientation,
}
