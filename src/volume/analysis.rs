//! Volume statistics. PLACEHOLDER — replaced by the topology work.

/// Value statistics of a volume.
#[derive(Debug, Clone, serde::Serialize)]
pub struct VolumeStats {
    pub min: f64,
    pub max: f64,
}

/// Voxels at or above a threshold and their 6-connected components.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ComponentCount {
    pub voxels: u64,
    pub components: usize,
}
