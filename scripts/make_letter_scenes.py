#!/usr/bin/env python3
"""Writes problems/scenes/letters/letter_<L>.json: the "SIGGRAPH" letters of paper Fig. 1 /
Table 3. A straight rod, at rest, whose initial node velocities are optimised so that after
100 frames its nodes lie on the letter (problems/letters.cpp, 0.5 m high at the origin).
Rod settings from paper Table 2 (Fig. 1 row) except two, both measured (scripts/letters_table.py
prints the horizon sweep; README "Differentiable simulation"):
* Bending and twist stiffness are 1e-2 N m^2, not Table 2's 1e2: with our bend-twist energy
  (1/2 l dw^T K dw per interior node, lib/rod_terms.hpp) a 1e2 rod cannot be bent into a letter
  by initial velocities at all (bending S costs ~1e3 J; measured: L-BFGS stops at a stationary
  normalised loss of 0.086). The paper's units for K_b evidently differ.
* The time step is 1 ms, not Table 2's 10 ms, so the 100 frames last 0.1 s ("after a few
  simulation frames", Fig. 1). Over 1 s (100 frames of 10 ms) the rod's stretch and bending
  waves cross it many times, and the best normalised loss any back-end reaches on S stalls at
  5e-3 to 6e-2; 0.1 s in 10 steps of 10 ms moves nodes by several edge lengths per step, and
  stalls at 4e-2. 100 steps of 1 ms resolve the motion and S reaches 1e-3.
The rod's length is the letter's arc length at 0.5 m (tests/test_optimization.cpp checks it
against problems/letters.cpp), so that the target needs no stretching."""
import json
import pathlib

HEIGHT = 0.5
# letter: (nodes, arc length of letter_polyline(letter) scaled to HEIGHT, in metres)
LETTERS = {
    "S": (61, 1.164436), "I": (17, 0.500000), "G": (65, 1.402436), "R": (69, 1.652449),
    "A": (49, 1.525514), "P": (86, 1.242419), "H": (61, 1.850000),
}

out = pathlib.Path(__file__).resolve().parent.parent / "problems" / "scenes" / "letters"
out.mkdir(parents=True, exist_ok=True)
for letter, (nodes, length) in LETTERS.items():
    start = [round(0.25 - length / 2, 6), -0.3, 0.0]
    end = [round(0.25 + length / 2, 6), -0.3, 0.0]
    scene = {
        "description": f"Letter {letter} (paper Fig. 1, Table 3): optimise the initial velocity of "
                       f"every node of a straight rod ({nodes} nodes, {length:.3f} m) so that after "
                       f"100 frames of 1 ms it spells '{letter}' (0.5 m high). Loss: squared node distances "
                       f"to the target, normalised by its initial value.",
        "time_step": 1e-3,
        "frames": 100,
        "gravity": [0, 0, 0],
        "solver": {"backend": "newton", "rotation": "lie", "tolerance": 1e-10, "max_iterations": 200},
        "rods": [{
            "name": letter,
            "shape": {"type": "line", "start": start, "end": end, "edges": nodes - 1},
            "mass": round(min(0.8, max(0.5, 0.4 * length)), 3),
            "radius": 0.01,
            "stretch_stiffness": 4e2, "shear_stiffness": 1e2, "bending_stiffness": [1e-2, 1e-2, 1e-2],
        }],
        "optimization": {
            "parameters": [{"kind": "rod_node_velocities", "rod": letter}],
            "objective": [{"term": "point_targets", "rod": letter, "letter": letter,
                           "height": HEIGHT, "origin": [0, 0, 0]}],
            "optimizer": "nlopt-lbfgs",
            "max_iterations": 100,
            "target_normalized_loss": 1e-3,
        },
    }
    (out / f"letter_{letter}.json").write_text(json.dumps(scene, indent=2) + "\n")
