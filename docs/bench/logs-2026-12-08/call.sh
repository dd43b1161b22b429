# Issue 28, 2026-12-08: the device call of this session (carry .gl .gpu-bin .gpu-data, built by
# ../logs-2026-12-07c/prep.sh, ../logs-2026-12-07d/prep.sh, then the manylod bench and test
# binaries and the gbuffer test binary of this session's commits, and prep-splat.sh; see
# .gpu-bin/built-from).
# The GPU tests first (each output in $OUT/<name>.txt), then the benches through
# ../logs-2026-12-06b/run.sh (results.tar), the most wanted first.
source docs/bench/device-env.sh
export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft CI=1
mkdir -p .gpu-bin/t && tar xJf .gpu-bin/tests.tar.xz -C .gpu-bin/t
(
  cd .gpu-bin/t
  for t in subdiv-adaptive-test ssaa-adaptive-test subdiv-gpu-test manylod-gpu-test; do
    timeout 25 ./$t > "$OUT/$t.txt" 2>&1; echo "$t rc=$?"
  done
  timeout 25 ./gbuffer-gpu_vs_cpu --include-ignored > "$OUT/gbuffer-gpu_vs_cpu.txt" 2>&1
  echo "gbuffer-gpu_vs_cpu rc=$?"
)
# Arguments: the bench specs to run instead of the default list (the first call: the most
# wanted first). The second call, after prep-indirect.sh:
#   bash docs/bench/logs-2026-12-08/call.sh "ind-old:60:indirect-gpu-1e1fc9b --quick" \
#     "ind:60:indirect-gpu --quick" "ind-1080:90:indirect-gpu --quick --vpls 256,1024" \
#     "c64:55:subdiv-gpu-c64" "c256:55:subdiv-gpu-c256" "f013d2d:50:subdiv-gpu-f013d2d"
[ $# -gt 0 ] || set -- "c128:65:subdiv-gpu-c128" "b1e174e:55:subdiv-gpu" \
  "ssaa:75:ssaa-gpu --quick" "manylod:80:manylod-gpu --quick" \
  "loadmin:70:manylod-gpu-loadmin --quick" "c64:55:subdiv-gpu-c64" \
  "c256:55:subdiv-gpu-c256" "f013d2d:50:subdiv-gpu-f013d2d"
bash docs/bench/logs-2026-12-06b/run.sh "$@"
