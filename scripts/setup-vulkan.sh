#!/usr/bin/env bash
# Installs Mesa's lavapipe (software Vulkan) when no Vulkan driver is present.
# Sourced by ./quickstart and .ci/run; needs root or sudo for apt-get.
have_vulkan_driver() {
    local d
    for d in /usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        compgen -G "$d/*.json" >/dev/null && return 0
    done
    [ -n "${VK_ICD_FILENAMES:-}${VK_DRIVER_FILES:-}" ]
}

ensure_vulkan_driver() {
    if have_vulkan_driver; then
        return 0
    fi
    echo "no Vulkan driver found: installing Mesa lavapipe (mesa-vulkan-drivers)" >&2
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq mesa-vulkan-drivers >/dev/null
}
