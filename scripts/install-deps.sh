#!/usr/bin/env bash
# Installs the Debian packages vtkSVDAG builds and runs with (idempotent; needs root or sudo).
# chromium and chromium-driver: the browser viewer's tests drive Debian's headless chromium.
# Mesa comes from bookworm-backports: Debian 12's own lavapipe has no ray tracing.
set -euo pipefail
SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive

BACKPORTS=/etc/apt/sources.list.d/vtksvdag-backports.sources
if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
  $SUDO tee "$BACKPORTS" >/dev/null <<'SRC'
Types: deb
URIs: http://deb.debian.org/debian
Suites: bookworm-backports
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
fi

PKGS=(
  build-essential cmake ninja-build pkg-config git
  libvtk9-dev python3-vtk9 python3-numpy python3-venv python3-dev
  zlib1g-dev libzstd-dev libtiff-dev
  libvulkan-dev glslang-tools spirv-tools vulkan-tools vulkan-validationlayers
  libglm-dev libopenexr-dev
  xvfb xauth
  chromium chromium-driver
)
missing=()
for p in "${PKGS[@]}" mesa-vulkan-drivers; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# The backports Mesa is the one with ray tracing; an older one counts as missing.
mesa_ver=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
case "$mesa_ver" in 2[5-9].*|[3-9]*) ;; *) missing+=(mesa-vulkan-drivers) ;; esac

if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${PKGS[@]}"
  $SUDO apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers
fi
