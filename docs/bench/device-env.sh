# Sourced by the device scripts under docs/bench/logs-*: unpacks the carried Vulkan loader,
# selects the NVIDIA driver, points the programs at the carried fixtures, records the GPU and
# defines `clock` (the SM clock now).
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee "$OUT/gpu.txt"
