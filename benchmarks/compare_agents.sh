#!/bin/bash
# The full-size agent comparison of docs/agents.md: greedy vs random vs CMA-ES vs PPO on case0
# replication from seeds 1 and 2 (budget 100, 5 runs) and on RQ2 generation (budget 50, 10 runs), 10 repetitions.
#
#   bash benchmarks/compare_agents.sh [OUT]          (default OUT=results/compare-full; ~2 h on 2 cores)
#
# If benchmarks/reproduce_paper.py has run (results/paper), its greedy stores are copied in first: the compare
# then replays them (same env seeds, same simulator: identical numbers, and the wall time counts the stored
# simulation time) instead of flying the greedy again. Every search resumes where it stopped when run again.
# PPO policies come from `surrealist train` (results/policies/ppo-replicate.zip, ppo-generate.zip).
set -euo pipefail
OUT=${1:-results/compare-full}
PAPER=results/paper
mkdir -p "$OUT"/rep-seed1/searches "$OUT"/rep-seed2/searches "$OUT"/gen/searches
for r in $(seq 0 9); do
  for pair in "rq1-seed1:rep-seed1/searches/greedy" "rq1-seed2:rep-seed2/searches/greedy" \
              "rq2:gen/searches/greedy-paper"; do
    src="$PAPER/${pair%%:*}-rep$r.sqlite"; dst="$OUT/${pair#*:}-rep$r.sqlite"
    if [ -f "$src" ] && [ ! -f "$dst" ]; then cp "$src" "$dst"; fi
  done
done
surrealist compare --env Surrealist-Replicate-v0 \
  --agents greedy,random,cmaes,ppo:results/policies/ppo-replicate.zip \
  --repetitions 10 --budget 100 --workers 2 --parallel 2 --out "$OUT"/rep-seed1
surrealist compare --env Surrealist-Replicate-v0 --seed surrealist_gym/data/rq1-seed2.yaml \
  --agents greedy,random,cmaes,ppo:results/policies/ppo-replicate.zip \
  --repetitions 10 --budget 100 --workers 2 --parallel 2 --out "$OUT"/rep-seed2
surrealist compare --env Surrealist-Generate-v0 \
  --agents greedy-paper,random,cmaes,ppo:results/policies/ppo-generate.zip \
  --repetitions 10 --budget 50 --workers 2 --parallel 2 --out "$OUT"/gen
