#!/usr/bin/env bash
# Runs every fuzz target for a bounded time and prints one line per target: its run time,
# executions and crashes. Needs the nightly toolchain and cargo-fuzz
# (`cargo install cargo-fuzz`). Usage: [TARGETS="a b"] fuzz/run.sh [SECONDS_PER_TARGET]
# (default 60).
# Seeds come from fuzz/seeds/<target>/ (made by fuzz/seeds.sh); anything that crashes lands
# in fuzz/artifacts/<target>/ and belongs in tests/hostile_input.rs as a regression.
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-60}
targets=(${TARGETS:-maze_text png npy obj ply pose_json weights model_config scene_import vae_file gltf})
cargo +nightly fuzz build -O "${targets[@]/#/}" >/dev/null 2>&1 || cargo +nightly fuzz build -O
printf '%-14s %8s %12s %8s\n' target seconds executions crashes
for t in "${targets[@]}"; do
  mkdir -p "corpus/$t" "artifacts/$t"
  seeds=()
  [ -d "seeds/$t" ] && seeds=("seeds/$t")
  log=$(mktemp)
  cargo +nightly fuzz run -O "$t" "corpus/$t" "${seeds[@]}" -- -max_total_time="$secs" \
    -rss_limit_mb=2048 -malloc_limit_mb=1024 >"$log" 2>&1 || true
  runs=$(grep -oE 'Done [0-9]+ runs' "$log" | grep -oE '[0-9]+' | tail -1 || true)
  crashes=$(find "artifacts/$t" -type f | wc -l)
  printf '%-14s %8s %12s %8s\n' "$t" "$secs" "${runs:-?}" "$crashes"
  rm -f "$log"
done
