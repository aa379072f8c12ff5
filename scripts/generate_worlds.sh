#!/usr/bin/env bash
# Regenerates the shipped worlds (worlds/NAME.xml) and their previews (worlds/NAME.png).
#
# Usage: scripts/generate_worlds.sh [GENERATE_WORLD_BIN [RENDER_ENVIRONMENT_BIN]]
#   Without arguments the tools are run with `rosrun hidden_rooms ...` (source the workspace first). Given the
#   generate_world binary, render_environment is taken from the same folder unless named too.
# The worlds are deterministic: the same seeds always give the same files.
set -euo pipefail

package_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
worlds_dir="${package_dir}/worlds"

if [[ $# -ge 1 ]]; then
  generate_world=("$1")
  render_environment=("${2:-$(dirname "$1")/render_environment}")
else
  generate_world=(rosrun hidden_rooms generate_world)
  render_environment=(rosrun hidden_rooms render_environment)
fi

# name size seed: seeds picked by looking at the previews (medium_1 is the demo's default world).
worlds=(
  "small_1 small 3"
  "small_2 small 15"
  "medium_1 medium 16"
  "medium_2 medium 5"
  "large_1 large 8"
  "large_2 large 5"
)

preview_dir="$(mktemp -d)"
trap 'rm -rf "${preview_dir}"' EXIT

mkdir -p "${worlds_dir}"
for entry in "${worlds[@]}"; do
  read -r name size seed <<< "${entry}"
  "${generate_world[@]}" --seed "${seed}" --size "${size}" --out "${worlds_dir}/${name}.xml"
  "${render_environment[@]}" "${worlds_dir}/${name}.xml" --out "${preview_dir}/${name}" > /dev/null
  cp "${preview_dir}/${name}/preview.png" "${worlds_dir}/${name}.png"
done
