#!/usr/bin/env bash
# The GPU path, measured: run from the repository root on a machine with an NVIDIA GPU.
#   OUT=/tmp/gpu_check bash benchmarks/gpu_check.sh
# 1. env-steps/s of the paper's Coexistence sweep (4 β × 20 seeds, one lockstep ensemble) on the
#    GPU (PyTorch update) and on the same machine's CPU (compiled update), one after the other;
# 2. the quick profile on the GPU and on the CPU, side by side (two processes each), wall time and
#    the result files of both (quick_runs.tgz) for comparing their metrics.
# Writes into $OUT: machine.txt, rates.jsonl, quick_cuda.log, quick_cpu.log, quick_runs.tgz.
set -uo pipefail
OUT=${OUT:-/tmp/gpu_check}
PY=${PYTHON:-python3}
WORK=$(mktemp -d)
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 MPLBACKEND=Agg PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
{
  date -u
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader
  echo "cpus: $(nproc)"
  "$PY" -c "import torch, numba, numpy; print('torch', torch.__version__, 'numba', numba.__version__, 'numpy', numpy.__version__)"
  git rev-parse --short HEAD 2>/dev/null || echo "tree: $(cat empathy_zoo/_version.py | tail -1)"
} > "$OUT/machine.txt" 2>&1
cat "$OUT/machine.txt"
for device in cuda cpu; do
  kernel=$([ "$device" = cuda ] && echo torch || echo numba)
  timeout 240 "$PY" benchmarks/gpu_path.py --device "$device" --kernel "$kernel" --seeds 20 --steps 2000 \
    2> "$WORK/rate_$device.err" | tee -a "$OUT/rates.jsonl" || tail -5 "$WORK/rate_$device.err"
done
run_quick() {  # $1: device
  local kernel; kernel=$([ "$1" = cuda ] && echo torch || echo numba)
  local start=$SECONDS
  timeout 300 "$PY" -m empathy_zoo.cli reproduce --profile quick --out "$WORK/quick_$1" --device "$1" \
    --update-kernel "$kernel" --workers 2 --no-progress > "$OUT/quick_$1.log" 2>&1
  echo "exit $? after $((SECONDS - start)) s wall (device $1, kernel $kernel, workers 2)" >> "$OUT/quick_$1.log"
}
run_quick cuda & run_quick cpu & wait
tail -2 "$OUT/quick_cuda.log" "$OUT/quick_cpu.log"
(cd "$WORK" && tar czf "$OUT/quick_runs.tgz" quick_cuda/runs/*.json quick_cpu/runs/*.json 2>/dev/null)
ls -la "$OUT"
