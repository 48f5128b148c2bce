#!/usr/bin/env bash
# Container entrypoint: the workspace environment, then the command (default: make mission).
# In docker/compose.yaml every service sets ROS_MASTER_URI to the master container and ROS_HOSTNAME to
# its own service name, so that nodes in different containers reach each other by name.
set -e
cd /opt/mbzirc
set +u
# shellcheck disable=SC1091
source /opt/mbzirc/env.sh
exec "$@"
