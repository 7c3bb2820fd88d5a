//! Particles on skeletal implicit surfaces (SPEC §3.2–3.3, seed 002 §3.2–4.4):
//! Witkin–Heckbert particle sampling ([`wh`]) over the host's cell list
//! ([`cells`]).
//!
//! ```text
//!  Scene ─pose(t)─▶ FieldInput ─┐
//!  start: projected marching-cubes vertices ─▶ Particles ─▶ Sampler::iterate
//!        host: cell list (rebuild on skin/2)          │ kernel particle_update
//!        host: fission, death, lost (WH94 rule)  ◀────┘ (mirror: wh::cpu)
//! ```
//!
//! Design notes, derivations and defaults: `docs/design/particles.md`.

pub mod animate;
pub mod cells;
pub mod network;
pub mod wh;

pub use cells::CellList;
pub use network::{Network, NetworkOptions};
pub use wh::{Particles, Sampler, WhOptions};

/// One step's outputs of `particle_update` or `network_update`: new
/// positions (and σ) and the per-particle state or field sample.
pub type StepOutput = (Vec<[f32; 4]>, Vec<[f32; 4]>);

/// Table `name` of a scene file as `T` (its defaults when absent); errors
/// name the file, line and key.
fn scene_table<T: serde::de::DeserializeOwned + Default>(
    text: &str,
    origin: &str,
    name: &str,
) -> crate::Result<T> {
    let table: toml::Table = toml::from_str(text).map_err(|e| {
        let at = (e.span()).map_or(crate::Position::Whole, |s| {
            crate::io::config::line_column(text, s.start)
        });
        crate::Error::format(
            origin,
            at,
            "a scene",
            crate::io::config::toml_message(text, &e),
        )
    })?;
    if !table.contains_key(name) {
        return Ok(T::default());
    }
    // Errors name the table's header line and serde's message (the key).
    let value = table.get(name).cloned().expect("checked above");
    T::deserialize(value).map_err(|e| {
        let key = format!("{name}.");
        let at = text
            .find(&format!("[{name}]"))
            .map_or(crate::Position::Whole, |o| {
                crate::io::config::line_column(text, o)
            });
        crate::Error::format(
            origin,
            at,
            format!("a valid [{name}] table"),
            format!("{} ({key}…)", e.message()),
        )
    })
}

/// Errors unless every `(key, value)` is positive and finite.
fn check_positive(origin: &str, table: &str, values: &[(&str, f64)]) -> crate::Result<()> {
    for (name, v) in values {
        if !(v.is_finite() && *v > 0.0) {
            return Err(crate::Error::format(
                origin,
                crate::Position::Field(format!("{table}.{name}")),
                "a positive finite number",
                v.to_string(),
            ));
        }
    }
    Ok(())
}
