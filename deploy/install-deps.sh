#!/usr/bin/env bash
# Installs robodiff's build and runtime dependencies from Debian 12's packages.
# Idempotent: when every package is already installed it makes no apt call at all.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  libeigen3-dev liburdfdom-dev nlohmann-json3-dev libcli11-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libsqlite3-dev sqlite3
  libcpp-httplib-dev  # robodiffd's HTTP listener (server/http): /metrics, probes, dashboard
  openssl  # robodiff security: the DDS Security keystore (certificates, S/MIME-signed XML)
  cyclonedds-dev cyclonedds-tools
  iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libiceoryx-binding-c-dev
  coinor-libipopt-dev libzstd-dev
  libarchive-dev  # the tar files of signed cache entries (robodiff cache export/import)
  libspdlog-dev libfmt-dev  # robodiffd's log lines (spdlog formats with fmt)
  libtomlplusplus-dev  # toml++: robodiffd.conf is TOML (server/robodiffd/src/config_file.cpp)
  clang tcc
  chromium chromium-driver  # the dashboard's test runs the page in headless Chromium
  python3-venv python3-dev  # the Python module: build/venv (python/setup-venv.sh) and Python's headers
  python3-matplotlib  # examples/python/plot_torques.py's PNG (optional for users; its test runs it)
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
