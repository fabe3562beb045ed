#!/usr/bin/env bash
# Mesa 25's lavapipe (Debian 12's bookworm-backports) beside the system's Mesa 22.3,
# for what the older one cannot run: Bevy's own Atmosphere crashes lavapipe 22.3 (a
# segmentation fault in a driver thread). Unpacks the package into target/lavapipe-25
# without installing it (the system's driver, which CI tests on, stays as it is) and
# prints the line that points Vulkan's loader at it:
#
#   eval "$(scripts/lavapipe-25.sh)"
#   cargo run -p bevy_atmo --example accuracy
#
# Needs root for apt-get's lists (it reads the backports' list into its own folder).
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$PWD/target/lavapipe-25
icd=$dir/lvp_icd.json
if [ ! -f "$icd" ]; then
  mkdir -p "$dir/lists/partial"
  echo 'deb http://deb.debian.org/debian bookworm-backports main' > "$dir/sources.list"
  apt=(-o "Dir::Etc::sourcelist=$dir/sources.list" -o Dir::Etc::sourceparts=-
       -o "Dir::State::Lists=$dir/lists" -o APT::Get::List-Cleanup=0)
  apt-get update "${apt[@]}" >&2
  (cd "$dir" && apt-get download "${apt[@]}" mesa-vulkan-drivers/bookworm-backports >&2)
  dpkg -x "$dir"/mesa-vulkan-drivers_*.deb "$dir/root"
  lib=$dir/root/usr/lib/x86_64-linux-gnu/libvulkan_lvp.so
  [ -f "$lib" ] || { echo "lavapipe-25: no $lib in the package" >&2; exit 1; }
  # The package's manifest names the library bare (found on the system's path): point
  # it at the unpacked one, through a temporary file renamed when whole.
  sed "s#\"libvulkan_lvp.so\"#\"$lib\"#" "$dir/root/usr/share/vulkan/icd.d/lvp_icd.json" > "$icd.tmp"
  mv "$icd.tmp" "$icd"
fi
echo "export VK_ICD_FILENAMES=$icd"
