//! What each kernel declares, read from its WGSL by naga once per process:
//! the bindings of group 0 with their kinds, the workgroup size and the
//! `u32` constants. The pass layer ([`super::pass`]) builds each pipeline's
//! bind-group layout from these facts and checks every binding a room makes
//! against them; nothing restates them by hand.

use std::sync::OnceLock;

use super::registry::{Kernel, preprocess};
use crate::error::{Error, Result};

/// How a kernel reads a binding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindKind {
    /// `var<uniform>`: the kernel's `Params`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

impl BindKind {
    /// The wgpu binding type of this kind.
    pub fn binding_type(self) -> wgpu::BufferBindingType {
        match self {
            BindKind::Uniform => wgpu::BufferBindingType::Uniform,
            BindKind::Read => wgpu::BufferBindingType::Storage { read_only: true },
            BindKind::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
        }
    }
}

/// The facts of one kernel, as its WGSL declares them.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelSpec {
    pub kernel: Kernel,
    /// `@group(0) @binding(i)` kinds, `i = 0..n` (the house order: uniform,
    /// then read-only, then read-write storage).
    pub bindings: Vec<BindKind>,
    /// `@workgroup_size(x)` of the entry point `main` (1-D).
    pub wg_size: u32,
    /// Every module-scope `const NAME: u32`, by name.
    pub consts: Vec<(String, u32)>,
}

impl KernelSpec {
    /// Value of the WGSL constant `name`.
    pub fn const_u32(&self, name: &str) -> Result<u32> {
        (self.consts.iter().find(|(n, _)| n == name))
            .map(|&(_, v)| v)
            .ok_or_else(|| Error::Kernel {
                name: self.kernel.name().into(),
                message: format!("declares no `const {name}: u32`"),
            })
    }
}

impl Kernel {
    /// This kernel's facts, reflected from its WGSL on first use.
    pub fn spec(self) -> Result<&'static KernelSpec> {
        static SPECS: OnceLock<Vec<std::result::Result<KernelSpec, String>>> = OnceLock::new();
        let specs = SPECS.get_or_init(|| Kernel::ALL.iter().map(|&k| reflect(k)).collect());
        let at = Kernel::ALL.iter().position(|&k| k == self).unwrap_or(0);
        specs[at].as_ref().map_err(|message| Error::Kernel {
            name: self.name().into(),
            message: message.clone(),
        })
    }
}

/// Parses `kernel`'s preprocessed WGSL and reads its facts.
fn reflect(kernel: Kernel) -> std::result::Result<KernelSpec, String> {
    let source = preprocess(kernel.source())?;
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    let mut bindings: Vec<(u32, BindKind)> = Vec::new();
    for (_, g) in module.global_variables.iter() {
        let Some(rb) = &g.binding else { continue };
        if rb.group != 0 {
            return Err(format!(
                "binding {} in group {} (only group 0 is bound)",
                rb.binding, rb.group
            ));
        }
        let kind = match g.space {
            naga::AddressSpace::Uniform => BindKind::Uniform,
            naga::AddressSpace::Storage { access }
                if access.contains(naga::StorageAccess::STORE) =>
            {
                BindKind::ReadWrite
            }
            naga::AddressSpace::Storage { .. } => BindKind::Read,
            other => return Err(format!("binding {} in address space {other:?}", rb.binding)),
        };
        bindings.push((rb.binding, kind));
    }
    bindings.sort_by_key(|b| b.0);
    if let Some((i, _)) = (bindings.iter().enumerate()).find(|(i, b)| b.0 != *i as u32) {
        return Err(format!(
            "bindings are not numbered 0..n (binding {i} missing)"
        ));
    }
    let [entry] = module.entry_points.as_slice() else {
        return Err(format!(
            "{} entry points, expected one `main`",
            module.entry_points.len()
        ));
    };
    if entry.name != "main" || entry.stage != naga::ShaderStage::Compute {
        return Err(format!(
            "entry point `{}` ({:?}), expected compute `main`",
            entry.name, entry.stage
        ));
    }
    let [wg_size, 1, 1] = entry.workgroup_size else {
        return Err(format!(
            "workgroup size {:?}, expected 1-D",
            entry.workgroup_size
        ));
    };
    let consts = (module.constants.iter())
        .filter_map(|(_, c)| match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => Some((c.name.clone()?, v)),
            _ => None,
        })
        .collect();
    Ok(KernelSpec {
        kernel,
        bindings: bindings.into_iter().map(|b| b.1).collect(),
        wg_size,
        consts,
    })
}
