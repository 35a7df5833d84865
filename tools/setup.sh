#!/usr/bin/env bash
# Installs every Debian 12 package Penumbra needs to build, test and run. Idempotent; run as root.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git clang clang-format libclang-rt-14-dev
  libembree-dev libtbb-dev libopenimageio-dev openimageio-tools
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler libssl-dev
  libspdlog-dev nlohmann-json3-dev libcli11-dev libsqlite3-dev libtinyobjloader-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev
  libplplot-dev plplot-driver-cairo fonts-dejavu-core libpolyclipping-dev
  python3 python3-yaml python3-jsonschema python3-prometheus-client
  chromium iproute2 iptables nftables openssl
  libcpp-httplib-dev python3-kubernetes
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
