#!/usr/bin/env python3
"""Ceres step back-end, "rotation": "lie": the chart (3 doubles, re-centred per solve) against
SO3Manifold (4 doubles, exact exponential), side by side on the same scenes.

  /usr/bin/python3 scripts/ceres_lie_blocks.py [--liedyn build/liedyn] [--repeat 3] [--frames N]

Each scene is copied with "solver": {"backend": "ceres", "ceres": {"lie_blocks": ...}} (and
its frames cut to --frames if given) and timed by `liedyn bench --json`. Prints one row per
scene and variant: median wall time, frames, iterations and assemblies per frame, unconverged
steps, and the manifold/chart time ratio.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

SCENES = ["problems/scenes/butterfly_bolt.json", "problems/scenes/helix_pull.json",
          "problems/scenes/contact/die_throw.json"]


def bench(liedyn, scene, repeat):
    out = subprocess.run([liedyn, "bench", str(scene), "--repeat", str(repeat), "--json"],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--liedyn", default="build/liedyn")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--frames", type=int, default=0, help="cut every scene to this many frames")
    parser.add_argument("scenes", nargs="*", default=SCENES)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print(f"{'scene':<22} {'lie_blocks':<9} {'seconds':>9} {'frames':>6} {'it/frame':>8} "
              f"{'asm/frame':>9} {'unconv':>6} {'ratio':>6}")
        for path in args.scenes:
            scene = json.loads(pathlib.Path(path).read_text())
            if args.frames:
                scene["frames"] = min(scene.get("frames", args.frames), args.frames)
            times = {}
            for blocks in ("chart", "manifold"):
                solver = dict(scene.get("solver", {}))
                solver["backend"] = "ceres"
                solver["rotation"] = "lie"
                solver["ceres"] = dict(solver.get("ceres", {}), lie_blocks=blocks)
                variant = dict(scene, solver=solver)
                file = pathlib.Path(tmp) / f"{pathlib.Path(path).stem}_{blocks}.json"
                file.write_text(json.dumps(variant))
                r = bench(args.liedyn, file, args.repeat)
                times[blocks] = r["total_seconds"]
                ratio = f"{times['manifold'] / times['chart']:.2f}" if blocks == "manifold" else ""
                print(f"{pathlib.Path(path).stem:<22} {blocks:<9} {r['total_seconds']:>9.4f} "
                      f"{r['frames']:>6} {r['iterations_per_frame']:>8.2f} "
                      f"{r['assemblies_per_frame']:>9.2f} {r['unconverged_steps']:>6} {ratio:>6}",
                      flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
