//! Exclusive scan. PLACEHOLDER.
