//! Headless previews. PLACEHOLDER.
