"""The files ledsim reads and writes: outputs that appear whole or not at all, strict JSON
results, and what the package ships (the MJCF scene, the trained checkpoints)."""
