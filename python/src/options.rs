//! Options as the command line names them (`--corners local26`,
//! `--level 500`, `--component largest`), parsed once for every binding.

use chisel::hull::{CoplanarPolicy, HullOptions, Order};
use chisel::voxel::{CandidateKind, Component, Selection};
use chisel::{Error, Result};

/// `corners`, `vertices`, `coplanar`, `order` of `chisel hull`, `scan`
/// and `polyhedrize`.
#[derive(Debug, Clone, Copy)]
pub struct HullArgs<'a> {
    pub corners: &'a str,
    pub vertices: &'a str,
    pub coplanar: &'a str,
    pub order: &'a str,
}

impl HullArgs<'_> {
    /// The candidate kind and hull options these names ask for.
    pub fn parse(&self) -> Result<(CandidateKind, HullOptions)> {
        let candidates = match (self.vertices, self.corners) {
            ("corners", _) => CandidateKind::ConvexCorners,
            ("voxels", "local6") => CandidateKind::Local6,
            ("voxels", "local18") => CandidateKind::Local18,
            ("voxels", "local26") => CandidateKind::Local26,
            ("voxels", "convex") => CandidateKind::ConvexVoxels,
            ("voxels", other) => {
                return Err(Error::unknown(
                    "corners",
                    other,
                    ["local6", "local18", "local26", "convex"],
                ));
            }
            (other, _) => return Err(Error::unknown("vertices", other, ["voxels", "corners"])),
        };
        let coplanar = match self.coplanar {
            "merge" => CoplanarPolicy::Merge,
            "visible" => CoplanarPolicy::Visible,
            "invisible" => CoplanarPolicy::Invisible,
            other => {
                return Err(Error::unknown(
                    "coplanar",
                    other,
                    ["merge", "visible", "invisible"],
                ));
            }
        };
        let order = match self.order {
            "furthest" => Order::Furthest,
            "extreme" => Order::ExtremeFirst,
            "lexicographic" => Order::Lexicographic,
            other => {
                return Err(Error::unknown(
                    "order",
                    other,
                    ["furthest", "extreme", "lexicographic"],
                ));
            }
        };
        Ok((candidates, HullOptions { coplanar, order }))
    }
}

/// `level` (samples ≥ T) or `label` (samples == L): exactly one of them,
/// not NaN (as the command line's `--level` / `--label`).
#[derive(Debug, Clone, Copy)]
pub enum Iso {
    Level(f64),
    Label(f64),
}

impl Iso {
    pub fn of(level: Option<f64>, label: Option<f64>) -> Result<Iso> {
        let iso = match (level, label) {
            (Some(t), None) => Iso::Level(t),
            (None, Some(l)) => Iso::Label(l),
            _ => {
                return Err(Error::param(
                    "level, label",
                    format!("{level:?}, {label:?}"),
                    "give exactly one of them",
                ));
            }
        };
        match iso {
            Iso::Level(v) | Iso::Label(v) if v.is_nan() => {
                Err(Error::param("level, label", "NaN", "must be a number"))
            }
            _ => Ok(iso),
        }
    }
}

/// A scan's `level` (`None`: labels); not NaN.
pub fn level(level: Option<f64>) -> Result<Option<f64>> {
    match level {
        Some(t) if t.is_nan() => Err(Error::param("level", "NaN", "must be a number")),
        other => Ok(other),
    }
}

/// The object of `chisel hull` / `polyhedrize`: `level` (samples ≥ T) or
/// `label` (samples == L), and `component` (`"largest"`, `"all"` or a
/// 1-based number as a string).
fn selection(
    level: Option<f64>,
    label: Option<f64>,
    component: &str,
) -> Result<(Selection, Component)> {
    let selection = match Iso::of(level, label)? {
        Iso::Level(t) => Selection::Threshold(t),
        Iso::Label(l) => Selection::Label(l),
    };
    let component = match component {
        "largest" => Component::Largest,
        "all" => Component::All,
        n => match n.parse::<usize>() {
            Ok(k) if k >= 1 => Component::Index(k),
            _ => {
                return Err(Error::param(
                    "component",
                    n,
                    "\"largest\", \"all\" or a component number from 1",
                ));
            }
        },
    };
    Ok((selection, component))
}

/// The object and hull options of `hull`, `hull_scan`, `polyhedrize`.
#[derive(Debug, Clone, Copy)]
pub struct ObjectArgs {
    pub selection: Selection,
    pub component: Component,
    pub candidates: CandidateKind,
    pub hull: HullOptions,
}

impl ObjectArgs {
    pub fn parse(
        level: Option<f64>,
        label: Option<f64>,
        component: &str,
        hull: HullArgs<'_>,
    ) -> Result<ObjectArgs> {
        let (selection, component) = selection(level, label, component)?;
        let (candidates, hull) = hull.parse()?;
        Ok(ObjectArgs {
            selection,
            component,
            candidates,
            hull,
        })
    }
}
