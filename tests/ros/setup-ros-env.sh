#!/usr/bin/env bash
# The ROS 2 environment for the ROS tests: the script ships in the package, so that an installed
# wheel has it too (src/dynevent/ros/setup/setup-ros-env.sh; --help there says all).
exec bash "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/../../src/dynevent/ros/setup/setup-ros-env.sh" "$@"
