#!/bin/bash
# Train the policy for every mission that ships as ppo-sample:pretrained (surrealist_gym/data/policies/ppo-missions.zip):
# PPO on drawn case studies (surrealist train --problem missions, 2 envs), in parts of 2048 steps, part k on random
# seed k - 1 and started from part k - 1's weights (--init); part 1 at PPO's default learning rate (3e-4), the later
# parts at 1e-3. A rerun skips the parts already in OUT and trains on.
#
#   bash benchmarks/train_pretrained.sh [PARTS] [OUT]      # default: 8 parts (16,384 steps) into results/pretrained
#
# Then `python benchmarks/ship_pretrained.py OUT` copies the last part into the package with the record of every part.
set -euo pipefail
parts=${1:-8}
out=${2:-results/pretrained}
surrealist=${SURREALIST:-surrealist}
mkdir -p "$out"
prev=""
for k in $(seq 1 "$parts"); do
  policy="$out/part$k.zip"
  if [ -f "$policy" ] && [ -f "$out/part$k.json" ]; then prev=$policy; continue; fi
  rate=()
  if [ "$k" -gt 1 ]; then rate=(--learning-rate 1e-3); fi
  $surrealist train --problem missions --steps 2048 --envs 2 --random-seed $((k - 1)) "${rate[@]}" \
    --policy "$policy" --overwrite ${prev:+--init "$prev"}
  prev=$policy
done
echo "trained $parts parts in $out; last: $prev"
