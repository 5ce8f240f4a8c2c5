#!/usr/bin/env bash
# Installs the Debian packages pamdp needs to build and test. Idempotent: prints nothing and
# touches nothing when every package is already installed. Needs root (or sudo) otherwise.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev            # the MLP
  libopenblas-dev          # the MLP's matrix products (core/gemm.hpp)
  libzmq3-dev cppzmq-dev   # transport between actors, replay shards and the learner
  libflatbuffers-dev flatbuffers-compiler  # wire and checkpoint format (flatc at build time)
  libspdlog-dev libfmt-dev # structured logs
  libcli11-dev             # the command line
  libtomlplusplus-dev      # config files
  nlohmann-json3-dev       # JSON in and out (--json, STATE.json)
  libgtest-dev libgmock-dev  # tests
  libbenchmark-dev         # pamdp-bench
  libcpp-httplib-dev       # the /metrics endpoint of every process (Prometheus text format)
  gnuplot-nox              # pamdp plot (learning-curve PNGs)
  prometheus               # the test that scrapes a running cluster with a real Prometheus
  clang-format             # tests/run.sh checks formatting
  python3-dev python3-pybind11 python3-numpy  # the Python module pamdp (python/) and its tests
  iproute2 iptables curl   # the network fault test: namespaces, veth, loss and partitions; /metrics scrapes
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
((${#missing[@]} == 0)) && exit 0

echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then
    SUDO="sudo"
  else
    echo "install-deps: need root to install: ${missing[*]} (run as root or install sudo)" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq >/dev/null
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
