#!/usr/bin/env bash
# Makes sure a Vulkan driver exists: with none installed, installs Mesa's software
# rasteriser (lavapipe) from Debian's packages. Needs root or sudo for apt-get.
set -euo pipefail
if ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
  exit 0
fi
echo "no Vulkan driver found: installing Mesa's lavapipe (mesa-vulkan-drivers)" >&2
sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq mesa-vulkan-drivers >/dev/null
