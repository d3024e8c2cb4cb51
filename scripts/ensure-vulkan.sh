#!/usr/bin/env bash
# Makes sure a Vulkan driver exists: with none installed, installs Mesa's software
# rasteriser (lavapipe) from Debian's packages. Installing needs root or sudo; without
# either, it says what to install and exits with status 2.
#
# A driver is found when any ICD manifest (*.json) lies in any of the loader's folders,
# or when VK_DRIVER_FILES / VK_ICD_FILENAMES name a file (or, for VK_DRIVER_FILES, a
# folder) that exists. MESHLIGHT_VULKAN_ICD_DIRS (colon-separated) replaces the folders
# searched, so the detection can be checked against folders made for the purpose.
set -euo pipefail

icd_dirs="${MESHLIGHT_VULKAN_ICD_DIRS:-/etc/vulkan/icd.d:/usr/local/etc/vulkan/icd.d:/usr/local/share/vulkan/icd.d:/usr/share/vulkan/icd.d}"

# Only shell builtins, so the check needs nothing from PATH.
driver_found() {
  local dir file dirs files
  IFS=: read -r -a dirs <<<"$icd_dirs"
  for dir in "${dirs[@]}"; do
    [ -n "$dir" ] && compgen -G "$dir/*.json" >/dev/null && return 0
  done
  IFS=: read -r -a files <<<"${VK_DRIVER_FILES:-}:${VK_ICD_FILENAMES:-}"
  for file in "${files[@]}"; do
    [ -n "$file" ] && [ -e "$file" ] && return 0
  done
  return 1
}

if driver_found; then
  exit 0
fi

install_hint="install Mesa's Vulkan drivers (lavapipe runs on any CPU), e.g.
  sudo apt-get install mesa-vulkan-drivers      (Debian, Ubuntu)
  sudo dnf install mesa-vulkan-drivers          (Fedora)
  sudo pacman -S vulkan-swrast                  (Arch)
or point VK_DRIVER_FILES at an ICD manifest (*.json) of an installed driver"

here="${BASH_SOURCE[0]%/*}"
[ "$here" = "${BASH_SOURCE[0]}" ] && here=.
source "$here/apt-install.sh"
apt_install "no Vulkan driver found (no *.json in ${icd_dirs//:/, })" mesa-vulkan-drivers "$install_hint"
if ! driver_found; then
  echo "error: mesa-vulkan-drivers was installed but no ICD manifest appeared in ${icd_dirs//:/, }" >&2
  exit 2
fi
