#!/usr/bin/env bash
# roslaunch env-loader for robots started on another machine (<machine env-loader=...>): sources the
# workspace environment (env.sh at the repository root, found from this file's place) and runs the command.
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../../.." && pwd)"
# shellcheck disable=SC1091
source "$ROOT/env.sh"
exec "$@"
