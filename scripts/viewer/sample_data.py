#!/usr/bin/env python3
"""Write a `liedyn view` page filled with synthetic data, to test the page template
(problems/viewer/view_template.html) without the C++ writer.

Usage: python3 scripts/viewer/sample_data.py OUT.html [--frames N] [--rod-edges E]
                                                     [--all-shapes] [--wrap W]

The scene: a spinning rounded box and a bouncing sphere (bodies), a swinging and twisting rod
(40 edges, radius 0.02), and plane, sphere, capsule, tube and mesh colliders. --all-shapes adds
a capsule, cylinder, torus, mesh, points and axes body and a rotated rounded box collider, so
every shape the page knows is drawn. The title holds "</script>" and a comment opener on
purpose: the page must survive them.

The template is filled exactly as its header comment says the C++ side does it: the four
placeholders are spliced in one pass; the JS libraries get every "</script" (any case) escaped
as "<\\/script"; the metadata JSON gets every "<" written as \\u003c; the frame floats are
little-endian float32 in base64. Only the standard library is used.
"""

import argparse
import array
import base64
import json
import math
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TEMPLATE = REPO / "problems" / "viewer" / "view_template.html"
THREE_DIR = Path("/usr/share/javascript/three")  # Debian's libjs-three (r111)
THREE_JS = THREE_DIR / "three.min.js"
ORBIT_JS = THREE_DIR / "examples" / "js" / "controls" / "OrbitControls.js"

PH_THREE = "/*LIEDYN_THREE_JS*/"
PH_ORBIT = "/*LIEDYN_ORBIT_CONTROLS_JS*/"
PH_META = "/*LIEDYN_META_JSON*/"
PH_FRAMES = "/*LIEDYN_FRAMES_BASE64*/"

TIME_STEP = 0.01
FRAME_EVERY = 5  # one written frame every 5 simulation frames, as `output.every` would do


# --- the escaping and filling contract (mirrors the template's header comment) -------------

_SCRIPT_END = re.compile(r"</(script)", re.IGNORECASE)


def escape_js(text):
    """A JS library's text, unable to end its script element: "</script" -> "<\\/script"."""
    return _SCRIPT_END.sub(r"<\\/\1", text)


def meta_json(meta):
    """The metadata as JSON with every "<" as \\u003c (JSON has "<" only inside strings)."""
    return json.dumps(meta, separators=(",", ":"), allow_nan=False).replace("<", "\\u003c")


def fill(template, values):
    """Splice each placeholder's value into the template in one pass (values are never
    searched for placeholders, and nothing in them is interpreted)."""
    spots = []
    for name, value in values.items():
        count = template.count(name)
        if count != 1:
            raise SystemExit(f"template: placeholder {name} occurs {count} times, expected once")
        spots.append((template.index(name), name, value))
    spots.sort()
    out, last = [], 0
    for pos, name, value in spots:
        out.append(template[last:pos])
        out.append(value)
        last = pos + len(name)
    out.append(template[last:])
    return "".join(out)


# --- rotations (quaternions as (w, x, y, z)) -----------------------------------------------

def quat_axis_angle(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    s = math.sin(angle / 2) / n
    return (math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s)


def quat_mul(p, q):
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw)


def quat_from_columns(d1, d2, d3):
    """Unit quaternion of the rotation whose matrix has columns d1, d2, d3 (Shepperd)."""
    m00, m10, m20 = d1
    m01, m11, m21 = d2
    m02, m12, m22 = d3
    tr = m00 + m11 + m22
    if tr > 0:
        s = 2 * math.sqrt(1 + tr)
        return (s / 4, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s)
    if m00 >= m11 and m00 >= m22:
        s = 2 * math.sqrt(1 + m00 - m11 - m22)
        return ((m21 - m12) / s, s / 4, (m01 + m10) / s, (m02 + m20) / s)
    if m11 >= m22:
        s = 2 * math.sqrt(1 + m11 - m00 - m22)
        return ((m02 - m20) / s, (m01 + m10) / s, s / 4, (m12 + m21) / s)
    s = 2 * math.sqrt(1 + m22 - m00 - m11)
    return ((m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, s / 4)


def rotate_z(v, a):
    c, s = math.cos(a), math.sin(a)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


# --- the synthetic scene --------------------------------------------------------------------

def scene(all_shapes, rod_edges):
    bodies = [
        {"name": "spinning box", "shape": {"type": "box", "half_extents": [0.12, 0.07, 0.04], "rounding": 0.015}},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.08}},
    ]
    if all_shapes:
        octa = [0.07, 0, 0, -0.07, 0, 0, 0, 0.07, 0, 0, -0.07, 0, 0, 0, 0.09, 0, 0, -0.09]
        octa_tris = [0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5]
        ring = []
        for i in range(24):
            a = 2 * math.pi * i / 24
            ring += [0.08 * math.cos(a), 0.08 * math.sin(a), 0.02 * math.sin(3 * a)]
        bodies += [
            {"name": "capsule", "shape": {"type": "capsule", "radius": 0.04, "half_length": 0.06}},
            {"name": "cylinder", "shape": {"type": "cylinder", "radius": 0.05, "half_length": 0.05}},
            {"name": "torus", "shape": {"type": "torus", "major_radius": 0.07, "minor_radius": 0.02}},
            {"name": "octahedron", "shape": {"type": "mesh", "vertices": octa, "triangles": octa_tris}},
            {"name": "samples", "shape": {"type": "points", "points": ring}},
            {"name": "unknown", "shape": {"type": "axes", "size": 0.08}},
        ]
    rods = [{"name": "S", "nodes": rod_edges + 1, "radius": 0.02}]
    pipe = []
    for i in range(21):
        u = i / 20
        pipe += [-0.9, -0.45 + 0.9 * u, 0.12 + 0.08 * math.sin(2 * math.pi * u)]
    pyramid = [0.55, 0.45, 0.0, 0.85, 0.45, 0.0, 0.85, 0.75, 0.0, 0.55, 0.75, 0.0, 0.7, 0.6, 0.2]
    colliders = [
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]},
        {"type": "sphere", "center": [0.0, 0.6, 0.18], "radius": 0.18, "inside": False},
        {"type": "capsule", "a": [-0.35, -0.5, 0.07], "b": [0.25, -0.65, 0.07], "radius": 0.07, "inside": False},
        {"type": "tube", "points": pipe, "radius": 0.06, "inside": True},
        {"type": "mesh", "vertices": pyramid, "triangles": [0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4, 0, 2, 1, 0, 3, 2],
         "inside": False},
    ]
    if all_shapes:
        c, s = math.cos(0.4), math.sin(0.4)
        colliders.append({"type": "box", "center": [-0.6, 0.6, 0.1], "half_extents": [0.15, 0.1, 0.1],
                          "rotation": [c, 0, 0, s], "rounding": 0.03, "inside": False})
    return bodies, rods, colliders


def body_pose(i, t):
    """Position and quaternion of body i at time t."""
    if i == 0:  # spinning box, bobbing above the plane
        q = quat_mul(quat_axis_angle((0.3, 0.2, 1.0), 2.5 * t), quat_axis_angle((1, 0, 0), 0.4))
        return (0.45, 0.0, 0.35 + 0.05 * math.sin(2 * math.pi * t / 3)), q
    if i == 1:  # ball bouncing on the plane, rolling about y
        return (-0.45, 0.1, 0.08 + 0.5 * abs(math.sin(math.pi * t / 1.5))), quat_axis_angle((0, 1, 0), 3 * t)
    # --all-shapes extras: a row at y = -1, each turning about its own tilted axis
    x = -0.75 + 0.3 * (i - 2)
    return (x, -1.0, 0.25), quat_axis_angle((math.sin(i), 0.5, 1.0), (1 + 0.2 * i) * t)


def rod_frame(t, edges, out):
    """Nodes and edge quaternions of the swinging rod at time t, appended to out.

    In its swing plane the centreline angle is phi(s) = theta(t) (1 - 0.8 s / L), integrated
    from the anchor; the whole rod turns about the vertical through the anchor by alpha(t);
    the edge frames twist about d3 by psi(s, t)."""
    anchor, length = (0.0, 0.0, 1.1), 0.9
    h = length / edges
    theta = 0.7 * math.sin(2 * math.pi * t / 2.4)
    alpha = 0.5 * math.sin(2 * math.pi * t / 5.0)
    q_turn = quat_axis_angle((0, 0, 1), alpha)
    x, z = 0.0, 0.0
    nodes = [(0.0, 0.0, 0.0)]
    quats = []
    for e in range(edges):
        s = (e + 0.5) * h
        phi = theta * (1 - 0.8 * s / length)
        d3 = (math.sin(phi), 0.0, -math.cos(phi))
        x += h * d3[0]
        z += h * d3[2]
        nodes.append((x, 0.0, z))
        d1 = (math.cos(phi), 0.0, math.sin(phi))
        d2 = (0.0, -1.0, 0.0)  # d3 x d1, so (d1, d2, d3) is right-handed
        psi = 1.5 * (s / length) * math.sin(2 * math.pi * t / 3.0)
        c, sn = math.cos(psi), math.sin(psi)
        e1 = tuple(c * a + sn * b for a, b in zip(d1, d2))
        e2 = tuple(-sn * a + c * b for a, b in zip(d1, d2))
        quats.append(quat_mul(q_turn, quat_from_columns(e1, e2, d3)))
    for p in nodes:
        r = rotate_z(p, alpha)
        out.extend((anchor[0] + r[0], anchor[1] + r[1], anchor[2] + r[2]))
    for q in quats:
        out.extend(q)


def build(frames, rod_edges, all_shapes):
    bodies, rods, colliders = scene(all_shapes, rod_edges)
    stride = 7 * len(bodies) + sum(3 * r["nodes"] + 4 * (r["nodes"] - 1) for r in rods)
    frame_numbers = [FRAME_EVERY * f for f in range(frames)]
    times = [round(n * TIME_STEP, 10) for n in frame_numbers]
    data = array.array("f")
    series = {"kinetic_energy": [], "potential_energy": [], "iterations": [], "max_penetration": []}
    for f, t in enumerate(times):
        row = []
        for i in range(len(bodies)):
            p, q = body_pose(i, t)
            row.extend(p)
            row.extend(q)
        rod_frame(t, rod_edges, row)
        assert len(row) == stride
        data.extend(row)
        swing = math.sin(2 * math.pi * t / 2.4)
        series["kinetic_energy"].append(0.8 * (1 - swing * swing) + 0.05 * math.sin(3 * t))
        series["potential_energy"].append(2.0 + 0.8 * swing * swing)
        series["iterations"].append(3 + (f * 7) % 5)
        series["max_penetration"].append(2e-4 * abs(math.sin(math.pi * t / 1.5 + 0.3)))
    if sys.byteorder != "little":
        data.byteswap()  # the contract is little-endian float32
    meta = {
        "title": 'synthetic sample: box, ball, rod </script><!-- "quoted" & <b>not bold</b>',
        "time_step": TIME_STEP,
        "frame_numbers": frame_numbers,
        "times": times,
        "bodies": bodies,
        "rods": rods,
        "colliders": colliders,
        "series": series,
    }
    return meta, data.tobytes()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="the page to write (e.g. /tmp/view.html)")
    ap.add_argument("--frames", type=int, default=300, help="written frames (default 300)")
    ap.add_argument("--rod-edges", type=int, default=40, help="edges of the rod (default 40)")
    ap.add_argument("--all-shapes", action="store_true", help="add a body of every shape and a box collider")
    ap.add_argument("--wrap", type=int, default=0, help="break the base64 into lines of W characters")
    args = ap.parse_args()
    if args.frames < 1 or args.rod_edges < 1:
        ap.error("--frames and --rod-edges must be >= 1")
    for path in (THREE_JS, ORBIT_JS):
        if not path.is_file():
            raise SystemExit(f"{path} is missing: apt-get install -y --no-install-recommends libjs-three")

    meta, raw = build(args.frames, args.rod_edges, args.all_shapes)
    b64 = base64.b64encode(raw).decode("ascii")
    if args.wrap > 0:
        b64 = "\n".join(b64[i:i + args.wrap] for i in range(0, len(b64), args.wrap))
    page = fill(TEMPLATE.read_text(encoding="utf-8"), {
        PH_THREE: escape_js(THREE_JS.read_text(encoding="utf-8")),
        PH_ORBIT: escape_js(ORBIT_JS.read_text(encoding="utf-8")),
        PH_META: meta_json(meta),
        PH_FRAMES: b64,
    })
    out = Path(args.out)
    out.write_text(page, encoding="utf-8")
    objects = len(meta["bodies"]) + len(meta["rods"]) + len(meta["colliders"])
    print(f"wrote {out}: {args.frames} frames, {objects} objects, {len(raw)} bytes of frames, "
          f"{out.stat().st_size} bytes")


if __name__ == "__main__":
    main()
