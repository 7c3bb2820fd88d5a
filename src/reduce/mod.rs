//! Min/max reductions. PLACEHOLDER.
