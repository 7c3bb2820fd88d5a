//! Adapter enumeration and choice (`CHISEL_ADAPTER`, `--adapter`).

use std::str::FromStr;

use crate::error::{Error, Result};

/// How to install a software adapter when none is found.
pub const LAVAPIPE_HINT: &str = "Install a Vulkan driver; without a GPU, Mesa's lavapipe \
     (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`) works everywhere.";

/// How to choose among the adapters found when the request matches none.
pub const PICK_HINT: &str = "Choose one of those by index or by a part of its name \
     (`--adapter 0`, `CHISEL_ADAPTER=llvmpipe`); `chisel info` lists them.";

/// Which adapter to open.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AdapterChoice {
    /// Prefer discrete, then integrated, then virtual, then CPU adapters.
    Auto,
    /// A CPU (software) adapter such as lavapipe.
    Cpu,
    /// The adapter with this index in enumeration order (`chisel info`).
    Index(usize),
    /// The first adapter whose name contains this text (case-insensitive).
    Name(String),
}

impl FromStr for AdapterChoice {
    type Err = Error;

    /// `auto`, `cpu`, `lavapipe`, `llvmpipe`, a number, or a name substring.
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim();
        Ok(match t.to_ascii_lowercase().as_str() {
            "" | "auto" => AdapterChoice::Auto,
            "cpu" | "lavapipe" | "llvmpipe" | "software" => AdapterChoice::Cpu,
            _ => match t.parse::<usize>() {
                Ok(i) => AdapterChoice::Index(i),
                Err(_) => AdapterChoice::Name(t.to_string()),
            },
        })
    }
}

impl std::fmt::Display for AdapterChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AdapterChoice::Auto => write!(f, "auto"),
            AdapterChoice::Cpu => write!(f, "cpu"),
            AdapterChoice::Index(i) => write!(f, "{i}"),
            AdapterChoice::Name(n) => write!(f, "{n}"),
        }
    }
}

impl AdapterChoice {
    /// Reads `CHISEL_ADAPTER`, falling back to wgpu's `WGPU_ADAPTER_NAME`, then `auto`.
    pub fn from_env() -> Result<Self> {
        if let Ok(v) = std::env::var("CHISEL_ADAPTER") {
            return v.parse();
        }
        if let Ok(v) = std::env::var("WGPU_ADAPTER_NAME") {
            return Ok(AdapterChoice::Name(v));
        }
        Ok(AdapterChoice::Auto)
    }
}

/// One adapter as `chisel info` reports it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AdapterReport {
    pub index: usize,
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    pub vendor: u32,
    pub device: u32,
    /// Optional features chisel uses, as the adapter offers them.
    pub shader_int64: bool,
    pub timestamp_query: bool,
    pub subgroup: bool,
    /// The limits chisel cares about.
    pub max_storage_buffer_binding_size: u64,
    pub max_buffer_size: u64,
    pub max_compute_workgroups_per_dimension: u32,
    pub max_compute_invocations_per_workgroup: u32,
    pub max_compute_workgroup_storage_size: u32,
    pub max_storage_buffers_per_shader_stage: u32,
    pub max_texture_dimension_2d: u32,
}

fn rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// `name (backend, type, driver)`.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({:?}, {:?}, {} {})",
        info.name, info.backend, info.device_type, info.driver, info.driver_info
    )
}

fn enumerate(instance: &wgpu::Instance) -> Vec<wgpu::Adapter> {
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
}

/// Every adapter the instance finds, in enumeration order.
pub fn adapter_reports(instance: &wgpu::Instance) -> Vec<AdapterReport> {
    enumerate(instance)
        .iter()
        .enumerate()
        .map(|(index, a)| {
            let info = a.get_info();
            let f = a.features();
            let l = a.limits();
            AdapterReport {
                index,
                name: info.name.clone(),
                backend: format!("{:?}", info.backend),
                device_type: format!("{:?}", info.device_type),
                driver: info.driver.clone(),
                driver_info: info.driver_info.clone(),
                vendor: info.vendor,
                device: info.device,
                shader_int64: f.contains(wgpu::Features::SHADER_INT64),
                timestamp_query: f.contains(wgpu::Features::TIMESTAMP_QUERY),
                subgroup: f.contains(wgpu::Features::SUBGROUP),
                max_storage_buffer_binding_size: l.max_storage_buffer_binding_size,
                max_buffer_size: l.max_buffer_size,
                max_compute_workgroups_per_dimension: l.max_compute_workgroups_per_dimension,
                max_compute_invocations_per_workgroup: l.max_compute_invocations_per_workgroup,
                max_compute_workgroup_storage_size: l.max_compute_workgroup_storage_size,
                max_storage_buffers_per_shader_stage: l.max_storage_buffers_per_shader_stage,
                max_texture_dimension_2d: l.max_texture_dimension_2d,
            }
        })
        .collect()
}

/// Picks the adapter `choice` names among those `instance` finds.
pub(crate) fn select(instance: &wgpu::Instance, choice: &AdapterChoice) -> Result<wgpu::Adapter> {
    // The GL backend duplicates Vulkan adapters with fewer features; only
    // fall back to it when nothing else exists.
    let all = enumerate(instance);
    let primary: Vec<&wgpu::Adapter> = all
        .iter()
        .filter(|a| a.get_info().backend != wgpu::Backend::Gl)
        .collect();
    let pool: Vec<&wgpu::Adapter> = if primary.is_empty() {
        all.iter().collect()
    } else {
        primary
    };
    let found = match choice {
        AdapterChoice::Auto => pool
            .iter()
            .min_by_key(|a| rank(a.get_info().device_type))
            .copied(),
        AdapterChoice::Cpu => pool
            .iter()
            .find(|a| a.get_info().device_type == wgpu::DeviceType::Cpu)
            .copied(),
        AdapterChoice::Index(i) => all.get(*i),
        AdapterChoice::Name(n) => {
            let n = n.to_lowercase();
            all.iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&n))
        }
    };
    found.cloned().ok_or_else(|| Error::NoAdapter {
        requested: choice.to_string(),
        available: all
            .iter()
            .enumerate()
            .map(|(i, a)| format!("{i}: {}", describe(&a.get_info())))
            .collect(),
        // With adapters present, a name or index that matches none wants
        // one of them, not a driver.
        hint: if all.is_empty() || matches!(choice, AdapterChoice::Auto | AdapterChoice::Cpu) {
            LAVAPIPE_HINT
        } else {
            PICK_HINT
        },
    })
}

/// The adapters and the one a choice opens: `chisel info`,
/// `chisel.gpu_info()`.
#[derive(Debug, serde::Serialize)]
pub struct InfoReport {
    /// chisel's version.
    chisel: &'static str,
    /// `--adapter` / `CHISEL_ADAPTER` as given.
    requested: String,
    adapters: Vec<AdapterReport>,
    chosen: Chosen,
}

impl crate::foundation::report::Report for InfoReport {
    const SCHEMA: &'static str = "chisel.info/1";
}

/// The adapter chosen, or why none could be opened.
#[derive(Debug, serde::Serialize)]
#[serde(untagged)]
pub enum Chosen {
    Opened {
        name: String,
        description: String,
        features: super::GpuFeatures,
        max_binding_bytes: u64,
    },
    Failed {
        error: String,
    },
}

/// The [`InfoReport`] of `choice`, and the device it opened (or why not).
pub fn info(choice: AdapterChoice) -> (InfoReport, Result<super::Gpu>) {
    let instance = super::instance();
    let adapters = adapter_reports(&instance);
    let chosen = super::Gpu::with_options(super::GpuOptions {
        adapter: Some(choice.clone()),
        ..Default::default()
    });
    let report = InfoReport {
        chisel: env!("CARGO_PKG_VERSION"),
        requested: choice.to_string(),
        adapters,
        chosen: match &chosen {
            Ok(gpu) => Chosen::Opened {
                name: gpu.info.name.clone(),
                description: gpu.describe(),
                features: gpu.features,
                max_binding_bytes: gpu.max_binding_bytes(),
            },
            Err(e) => Chosen::Failed {
                error: e.to_string(),
            },
        },
    };
    (report, chosen)
}
