//! `chisel info`: the adapter list and the choice of adapter.

use crate::common;
use crate::support::{chisel, ok_json};

#[test]
fn info_lists_adapters_as_json() {
    let Some(_gpu) = common::gpu() else { return };
    let v = ok_json(&["info", "--json"]);
    let adapters = v["adapters"].as_array().expect("adapters array");
    assert!(!adapters.is_empty());
    assert!(
        adapters[0]["max_storage_buffer_binding_size"]
            .as_u64()
            .unwrap()
            > 0
    );
    assert!(v["chosen"]["name"].is_string(), "{v}");
}

#[test]
fn unknown_adapter_is_a_clear_error() {
    let out = chisel(&["info", "--adapter", "no-such-adapter-xyz"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no GPU adapter matches `no-such-adapter-xyz`"),
        "{stderr}"
    );
    // A driver is the advice only when there is no adapter at all;
    // otherwise the user is pointed at the ones found.
    if stderr.contains("found: []") {
        assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
    } else {
        assert!(
            stderr.contains("Choose one of those") && !stderr.contains("mesa-vulkan-drivers"),
            "{stderr}"
        );
    }
}
