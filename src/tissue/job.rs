//! A relaxation's inputs, ready to run: the plan's bone cuts applied,
//! the spring network built (`chisel relax`, `chisel demo`, `chisel.relax`
//! in Python).

use std::collections::BTreeMap;

use serde::Serialize;

use super::{
    Fragments, NetworkParams, Plan, RelaxOptions, RelaxReport, SpringNetwork, cut_bone,
    fragments::PieceInfo,
};
use crate::cut::CutStats;
use crate::gpu::Backend;
use crate::{Error, Result, TriMesh};

/// A relaxation's inputs, ready to run.
#[derive(Debug)]
pub struct Job {
    pub skin: TriMesh,
    /// The bone mesh after the plan's cuts (`None`: the scaled skin).
    pub bone: Option<TriMesh>,
    pub network: SpringNetwork,
    pub plan: Plan,
    pub fragments: Fragments,
    /// What the plan's cuts did (`None` without cuts).
    pub cut: Option<BoneCutFigures>,
}

/// What the plan's cuts did to the bone: its pieces, the vertices of each
/// named fragment, and per cut what the scalpel did.
#[derive(Debug, Clone, Serialize)]
pub struct BoneCutFigures {
    pub pieces: Vec<PieceInfo>,
    pub fragments: BTreeMap<String, usize>,
    pub knives: Vec<CutStats>,
}

impl Job {
    /// Cuts `bone` with the plan's knives (fragments named after the cuts,
    /// merged with `fragments`) and builds the network over the result.
    ///
    /// Errors: a plan with cuts but no bone mesh, the cuts' and the
    /// network's errors.
    pub fn build(
        skin: TriMesh,
        bone: Option<TriMesh>,
        plan: Plan,
        mut fragments: Fragments,
        params: &NetworkParams,
    ) -> Result<Job> {
        let (bone, cut) = match (bone, plan.cuts.is_empty()) {
            (bone, true) => (bone, None),
            (None, false) => {
                return Err(Error::param(
                    "bone",
                    "none",
                    format!(
                        "the plan cuts the bone ({} `[[cut]]`), which needs a bone mesh \
                         (--bone-mesh or --ct)",
                        plan.cuts.len()
                    ),
                ));
            }
            (Some(b), false) => {
                let cut = cut_bone(&b, &plan.cuts, plan.source.as_deref())?;
                let report = BoneCutFigures {
                    fragments: cut
                        .fragments
                        .iter()
                        .map(|(k, v)| (k.clone(), v.len()))
                        .collect(),
                    pieces: cut.pieces,
                    knives: cut.stats,
                };
                fragments.extend(cut.fragments);
                (Some(cut.mesh), Some(report))
            }
        };
        let network = SpringNetwork::build(&skin, bone.as_ref(), params)?;
        Ok(Job {
            skin,
            bone,
            network,
            plan,
            fragments,
            cut,
        })
    }

    /// Resolves the plan on the network and relaxes it on `backend`.
    pub fn run(&self, opts: &RelaxOptions, backend: Backend<'_>) -> Result<RelaxReport> {
        let resolved = self.plan.resolve(&self.network, &self.fragments)?;
        super::relax(&self.network, &resolved, opts, backend)
    }
}
