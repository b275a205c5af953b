#!/usr/bin/env python3
"""Writes problems/scenes/contact/knot.json: a soft cord tied in a loose open overhand knot
whose ends are pulled apart until the knot is tight (DisMech's knot-tying case in spirit).
Python standard library only: `/usr/bin/python3 scripts/make_knot_scene.py [--out FILE]`.

The knot. A closed trefoil, the (2, 3) torus knot on a torus of radii 2 and 1 (design units u),
    K(t) = ((2 + cos 3t) cos(2t + pi/2), (2 + cos 3t) sin(2t + pi/2), sin 3t),   t in [0, 2 pi),
has its top lobe (t = 0, at (0, 3, 0)) cut open over |t| < T_CUT. Each cut end is joined by a
cubic Hermite arc to a straight tail along -x (the end at t = T_CUT, on the left) or +x (the
end at 2 pi - T_CUT), both on the line y = TAIL_HEIGHT, z = 0 above the knot. The arcs and
tails stay above the knot, where only the removed lobe tip was (and pass no strand closer than
the knot's own clearance, checked below), so closing the tails by a far arc above gives back
the trefoil: the open curve is an overhand knot. The curve is
symmetric under the half turn about the y axis, (x, y, z) -> (-x, y, -z), which the pull keeps.

Scale. The torus knot's closest approach of two strands that are not neighbours along it is
1.664 u (checked below on the nodes: the closest distance between edges a loop's length or
more apart along the cord); u is chosen so that this clearance is CLEARANCE_DIAMETERS cord diameters, centre
line to centre line: the knot is loose (the closest strands 2 diameters apart, surface to
surface). In the world the design plane xy becomes the vertical plane xz, (x, y, z) ->
(x, -z, y - TAIL_HEIGHT): the tails lie on the x axis and the knot hangs below them.

The cord. A 6 mm shock cord (rubber core in a braided sheath): 26 g/m, soft in bending and
stretchy, EA = 100 N (it stretches by 1 % under 1 N), EI = 5e-5 N m^2 (E ~ 0.8 MPa over the
section), twist GJ = 3.3e-5 N m^2 (G = E/3, incompressible rubber: GJ = 2 EI/3), shear
stiffness EA/3 = 33 N (the edges hardly shear). The stretchiness matters: the ends are pulled
by prescribed displacements, so once the knot is tight every further millimetre of pull
raises the tension by EA/L x 1 mm = 0.17 N; a stiff rope would crush its own contacts instead.
Its rest shape is straight (a cord tied into a knot). The knot starts bent away from its rest
shape, not in equilibrium: in the first tenth of a second it springs into a rounder loop whose
strands braid, before the pull tightens it.

Contact. Self-contact on (edges as capsules of the cord's radius, lib/edge_contact.hpp),
frictionless (rod-rod friction is not modelled), k = 1e4 N/m per edge, i.e. 1e4/l N/m^2 per
unit length for edges of length l = 3.9 mm: pulled tight at about 7 N, the strands of the
knot overlap by 0.6 mm at most, a fifth of the radius. SKIP = 3: edges touch when more than 3
apart along the cord, with 3 edges (3.9 radii) of cord between them, so that the tightest
bends of the knot do not bring neighbours into contact (with 2, 2.6 radii of cord bent to a
radius of one radius would overlap; this run's bends stay wider, and with 2 it comes out the
same: closest surfaces -0.60 mm).

The pull. Both clamped ends (node and edge: held in hands) move apart along x by PULL each,
at 0.2 m/s, then hold for HOLD_TIME; gravity is on, so the slack cord sags until it is
pulled taut. h = 1 ms: the largest node motion per step stays below the cord's radius
(tests/test_knot_and_dice_scenes.cpp checks it, with the argument why no crossing can then
pass between two frames unseen).
"""
import argparse
import json
import math
import pathlib
import re

# Cord (SI units).
RADIUS = 0.003
LINEAR_DENSITY = 0.026  # kg/m
STRETCH = 100.0         # EA, N
SHEAR = 33.0            # GA, N
BENDING = 5e-5          # EI, N m^2
TWIST = 3.3e-5          # GJ, N m^2
CONTACT_STIFFNESS = 1e4  # N/m per edge (per unit length: over the edge's rest length)
SKIP = 3
EDGES = 150
# Knot geometry (design units u unless stated).
T_CUT = 0.45                # the top lobe, |t| < T_CUT, is removed
TAIL_HEIGHT = 3.5           # the tails' line, y = TAIL_HEIGHT
BLEND_END = 3.0             # the arcs end on it at x = -+BLEND_END
CLEARANCE_DIAMETERS = 3.0   # closest non-neighbouring strands, centre to centre, in diameters
TORUS_CLEARANCE = 1.664     # of the torus knot, in u (checked on the nodes below)
TAIL_LENGTH = 0.12          # m, straight tail beyond each arc
# Motion.
TIME_STEP = 0.001
PULL = 0.13        # m, each end
PULL_TIME = 0.65   # s
HOLD_TIME = 0.25   # s


def torus_knot(t):
    rho = 2.0 + math.cos(3.0 * t)
    a = 2.0 * t + 0.5 * math.pi
    return (rho * math.cos(a), rho * math.sin(a), math.sin(3.0 * t))


def torus_knot_tangent(t, dt=1e-6):
    p, q = torus_knot(t + dt), torus_knot(t - dt)
    return tuple((x - y) / (2.0 * dt) for x, y in zip(p, q))


def hermite(p0, m0, p1, m1, n):
    """n + 1 points of the cubic from p0 (tangent m0) to p1 (tangent m1)."""
    out = []
    for i in range(n + 1):
        s = i / n
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        out.append(tuple(h00 * a + h10 * b + h01 * c + h11 * d for a, b, c, d in zip(p0, m0, p1, m1)))
    return out


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def design_curve(samples_per_part=4000):
    """The open knot as a fine polyline (design units): left tail, arc, knot, arc, right tail."""
    core = [torus_knot(T_CUT + (2.0 * math.pi - 2.0 * T_CUT) * i / samples_per_part)
            for i in range(samples_per_part + 1)]
    left, right = (-BLEND_END, TAIL_HEIGHT, 0.0), (BLEND_END, TAIL_HEIGHT, 0.0)
    d0, d1 = math.dist(left, core[0]), math.dist(core[-1], right)
    u0, u1 = unit(torus_knot_tangent(T_CUT)), unit(torus_knot_tangent(2.0 * math.pi - T_CUT))
    # Tangent lengths 0.7 d: arcs that leave the tail line flat and meet the knot smoothly.
    arc0 = hermite(left, (0.7 * d0, 0.0, 0.0), core[0], tuple(0.7 * d0 * x for x in u0), samples_per_part // 4)
    arc1 = hermite(core[-1], tuple(0.7 * d1 * x for x in u1), right, (0.7 * d1, 0.0, 0.0), samples_per_part // 4)
    return arc0[:-1] + core + arc1[1:]


def to_world(p, scale):
    x, y, z = p
    return (scale * x, -scale * z, scale * (y - TAIL_HEIGHT))


def equal_chords(polyline, edges):
    """edges + 1 points on the polyline from its first to its last point, consecutive ones the
    same straight distance apart (the chord length found by bisection)."""
    def march(chord):
        pts, seg, prev = [polyline[0]], 0, polyline[0]
        while len(pts) < edges + 1:
            # Advance along the polyline to the first point at distance >= chord from prev.
            while seg < len(polyline) - 1 and math.dist(prev, polyline[seg + 1]) < chord:
                seg += 1
            if seg == len(polyline) - 1:
                return pts, False
            a, b = polyline[seg], polyline[seg + 1]
            lo, hi = 0.0, 1.0
            if math.dist(prev, a) >= chord:
                lo = hi = 0.0
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                q = tuple(x + mid * (y - x) for x, y in zip(a, b))
                lo, hi = (mid, hi) if math.dist(prev, q) < chord else (lo, mid)
            prev = tuple(x + hi * (y - x) for x, y in zip(a, b))
            pts.append(prev)
        return pts, True

    length = sum(math.dist(polyline[i], polyline[i + 1]) for i in range(len(polyline) - 1))
    lo, hi = 0.5 * length / edges, length / edges
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        pts, complete = march(mid)
        lo, hi = (mid, hi) if complete else (lo, mid)
    pts, _ = march(lo)
    pts[-1] = polyline[-1]
    return pts, lo


def segment_distance(a0, a1, b0, b1):
    """Closest distance between two segments (every end case tried, as lib/edge_contact.hpp)."""
    def sub(p, q):
        return tuple(x - y for x, y in zip(p, q))

    def dot(p, q):
        return sum(x * y for x, y in zip(p, q))

    def point_segment(p, s0, s1):
        e = sub(s1, s0)
        ee = dot(e, e)
        t = 0.0 if ee == 0.0 else min(1.0, max(0.0, dot(sub(p, s0), e) / ee))
        return math.dist(p, tuple(x + t * y for x, y in zip(s0, e)))

    best = min(point_segment(a0, b0, b1), point_segment(a1, b0, b1),
               point_segment(b0, a0, a1), point_segment(b1, a0, a1))
    d1, d2, r = sub(a1, a0), sub(b1, b0), sub(a0, b0)
    a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)
    denom = a * e - b * b
    if denom > 1e-14 * a * e:
        s = min(1.0, max(0.0, (b * f - c * e) / denom))
        pa = tuple(x + s * y for x, y in zip(a0, d1))
        best = min(best, point_segment(pa, b0, b1))
    return best


def min_separation(nodes, skip):
    """The smallest surface distance (centre lines less a diameter) of edges more than skip apart."""
    best = math.inf
    n = len(nodes) - 1
    for i in range(n):
        for j in range(i + skip + 1, n):
            best = min(best, segment_distance(nodes[i], nodes[i + 1], nodes[j], nodes[j + 1]) - 2.0 * RADIUS)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    root = pathlib.Path(__file__).resolve().parent.parent
    parser.add_argument("--out", type=pathlib.Path, default=root / "problems/scenes/contact/knot.json")
    args = parser.parse_args()

    scale = CLEARANCE_DIAMETERS * 2.0 * RADIUS / TORUS_CLEARANCE
    knot = [to_world(p, scale) for p in design_curve()]
    left_end, right_end = knot[0], knot[-1]
    tail_points = 200
    polyline = ([(left_end[0] - TAIL_LENGTH * (1 - i / tail_points), 0.0, 0.0) for i in range(tail_points)] + knot +
                [(right_end[0] + TAIL_LENGTH * i / tail_points, 0.0, 0.0) for i in range(1, tail_points + 1)])
    nodes, edge_length = equal_chords(polyline, EDGES)
    length = edge_length * EDGES
    # Edges SKIP + 1 apart along a bend are closer than the knot's strands; the strands that
    # cross are edges at least a loop's length apart: their clearance is the torus knot's.
    separation = min_separation(nodes, SKIP)
    far = round(2.0 * math.pi * scale / edge_length)
    clearance = min_separation(nodes, far) + 2.0 * RADIUS
    assert abs(clearance / (CLEARANCE_DIAMETERS * 2.0 * RADIUS) - 1.0) < 0.02, clearance
    span = math.dist(nodes[0], nodes[-1])
    frames = round((PULL_TIME + HOLD_TIME) / TIME_STEP)

    scene = {
        "description": (
            f"An overhand knot pulled tight (DisMech's knot-tying case in spirit): a 6 mm shock cord "
            f"({EDGES} edges, {length:.3f} m, {LINEAR_DENSITY * 1000:.0f} g/m; EA = {STRETCH:g} N, "
            f"EI = {BENDING:g} N m^2, straight at rest) tied in a loose open trefoil (a (2,3) torus knot "
            f"with its top lobe cut open into straight tails; closest strands {CLEARANCE_DIAMETERS:g} "
            f"diameters apart, centre to centre; written by scripts/make_knot_scene.py). Its clamped ends "
            f"({span:.3f} m apart) are pulled apart along x by {PULL:g} m each over {PULL_TIME:g} s and held "
            f"for {HOLD_TIME:g} s: the knot tightens. Self-contact on (edges more than {SKIP} apart touch as "
            f"capsules of the cord's radius, lib/edge_contact.hpp; frictionless), k = {CONTACT_STIFFNESS:g} N/m "
            f"per edge; gravity on. frames.csv reports min_rod_separation: it never falls below minus the "
            f"cord's radius."),
        "time_step": TIME_STEP,
        "frames": frames,
        "gravity": [0, 0, -9.81],
        "solver": {"backend": "newton", "rotation": "lie", "tolerance": 1e-9, "max_iterations": 50},
        "rods": [{
            "name": "cord",
            "nodes": [[round(c, 9) for c in p] for p in nodes],
            "rest_shape": {"type": "line", "start": [0, 0, 0], "end": [round(length, 12), 0, 0], "edges": EDGES},
            "mass": round(LINEAR_DENSITY * length, 9),
            "radius": RADIUS,
            "stretch_stiffness": STRETCH,
            "shear_stiffness": SHEAR,
            "bending_stiffness": [BENDING, BENDING, TWIST],
            "fixed_nodes": [0, EDGES],
            "fixed_edges": [0, EDGES - 1],
            "prescribed_motions": [
                {"nodes": [0], "edges": [0], "keyframes": [{"time": PULL_TIME, "translation": [-PULL, 0, 0]}]},
                {"nodes": [EDGES], "edges": [EDGES - 1],
                 "keyframes": [{"time": PULL_TIME, "translation": [PULL, 0, 0]}]},
            ],
            "contact": {"stiffness": CONTACT_STIFFNESS, "self_contact": True, "self_contact_skip": SKIP},
        }],
    }
    # One node (any array of numbers) per line.
    text = re.sub(r"\[\s+([^\[\]{}]*?)\s+\]", lambda m: "[" + " ".join(m.group(1).split()) + "]",
                  json.dumps(scene, indent=1))
    args.out.write_text(text + "\n")
    print(f"{args.out}: {EDGES} edges of {edge_length * 1000:.3f} mm ({length:.4f} m), ends {span:.4f} m apart, "
          f"closest strands {clearance * 1000:.2f} mm apart (centre lines), surfaces of edges more than {SKIP} apart "
          f"at least {separation * 1000:.2f} mm apart, {frames} frames")


if __name__ == "__main__":
    main()
