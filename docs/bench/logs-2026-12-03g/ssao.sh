# The second ssao run of the day, at commit a58102d (with the smoothing after pass 2): the same
# device script as the first run's, with .gpu-bin/ssao-gpu built at that commit.
bash docs/bench/logs-2026-12-03f/ssao.sh
# Afterwards the three sheets were re-encoded as 8-bit grey PNGs (R = G = B checked per pixel), a third of the size.
