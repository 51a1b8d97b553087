#!/usr/bin/env bash
# Every tuning study of docs/results/methods/tuning, by the protocol of docs/tuning.md: the same
# learner space, trials, tuning seeds, budget and objective for every method, DQN included.
#   bash docs/results/methods/tuning/tune_all.sh [coexistence_v0|sharing_v0] ...
# (both variants unless named; run one variant per process to use two cores). A finished study is
# read back from its journal in seconds; a stopped one resumes where it stopped.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../../../.."   # (the repository's root: the paths below are relative)
here=docs/results/methods/tuning
TUNE=(--trials 10 --tuning-seeds 2 --budget 50000 --eval-interval 10000 --objective-over curve
      --param learning_rate=log:1e-4:3e-3 --update-kernel numba --no-progress)
declare -A METHODS=(
  [coexistence_v0]="dqn empathic_dqn empathic_dqn_in_view empathic_dqn_silver dqn_harm_penalty dqn_inequity_aversion
                    dqn_social_value dqn_aup dqn_relative_reachability dqn_considerate dqn_lagrangian"
  [sharing_v0]="dqn empathic_dqn empathic_dqn_in_view empathic_dqn_silver dqn_equality dqn_inequity_aversion
                dqn_social_value dqn_aup dqn_considerate"
)
variants=("$@")
[ ${#variants[@]} -gt 0 ] || variants=(coexistence_v0 sharing_v0)
for env in "${variants[@]}"; do
  [ -n "${METHODS[$env]:-}" ] || { echo "tune_all.sh: no studies for '$env' (coexistence_v0, sharing_v0)" >&2; exit 2; }
  for method in ${METHODS[$env]}; do
    nice empathy-zoo tune methods --method "$method" --env "$env" "${TUNE[@]}" --out "$here/$env/$method"
  done
done
