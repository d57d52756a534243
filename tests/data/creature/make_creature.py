#!/usr/bin/env python3
"""Writes the synthetic creatures of tests/data/creature (issue 11, the any-skeleton path); standard library only.

creature.gltf — a four-legged animal with a tail, skinned and animated, whose segmentation is known exactly:
  the surface of a union of cubes of 0.1 units (every face shared by a filled and an empty cube; vertices on the
  grid, shared), Y up, the head end at +Z, the character's left at +X:
    trunk   x [-0.3, 0.3)  y [0.8, 1.2)  z [-1.0, 1.0)    (6 × 4 × 20 cubes)
    legs    x [0.1, 0.3) left / [-0.3, -0.1) right,  z [-0.9, -0.7) hind / [0.7, 0.9) fore,  y [0, 0.8)  (2 × 8 × 2)
    tail    x [-0.1, 0.1)  y [1.0, 1.2)  z [-1.6, -1.0)   (2 × 2 × 6)
  Faces: trunk 2(6·4 + 6·20 + 4·20) − 4·4 (leg tops) − 4 (tail root) = 428, each leg 4·16 + 4 = 68, the tail
  4·12 + 4 = 52 — 752 quads, 1504 triangles (trunk 856, each leg 136, tail 104).
  Bones (nodes, translations only; rest rotations identity): Spine (root, y 1.0, z 0) → Pelvis (z −0.8) →
  {Tail01 (z −1.0) → Tail02 (z −1.3), HindLeg_L_01 (x 0.2, y 0.8) → HindLeg_L_02 (y 0.4), HindLeg_R_01 → _02};
  Spine → Chest (z 0.8) → {ForeLeg_L_01 → _02, ForeLeg_R_01 → _02}.
  Skin (rigid): a vertex of a leg below y 0.8 follows its leg (_02 below y 0.4), one of the tail behind z −1.0
  its tail (Tail02 behind z −1.3), a trunk vertex Pelvis (z < −0.3), Chest (z > 0.3) or Spine; a vertex on a
  part's junction with the trunk (the leg's ring at y 0.8, the tail's at z −1.0) is half the part's first bone,
  half the trunk bone it hangs from — so every triangle's largest summed weight is that of the cube it bounds,
  and the any-skeleton path must find exactly the five parts above and the trunk.
  Clips: "cross" (1 s): the left fore leg swings 35° about the body's long axis under the chest across the
  right one and back (exact triangle contacts between the two fore legs around t = 0.5 s); "still" (1 s):
  nothing moves.

snake.gltf — the same construction for a chain with no limbs: a 2 × 2 × 20 bar along Z skinned to a chain of
  four bones (Seg0 → Seg1 → Seg2 → Seg3): the any-skeleton path must refuse it ("no recognisable limbs").

figure.gltf — a standing humanoid whose bones are named node0…node12 and whose geometry misleads the
  geometry segmentation (figure() below): `--segmentation auto` must bake it by its bone tree (four limbs,
  head, trunk).

Run from anywhere: python3 tests/data/creature/make_creature.py (writes beside itself). Deterministic.
"""
import base64
import json
import math
import os
import struct

H = 0.1  # cube edge


def boxes_surface(boxes):
    """boxes: list of (part, (x0, x1), (y0, y1), (z0, z1)) in cube units. Returns vertices (grid points),
    quads (4 vertex indices, counter-clockwise seen from outside) and the part of the cube each quad bounds."""
    filled = {}
    for part, (x0, x1), (y0, y1), (z0, z1) in boxes:
        for x in range(x0, x1):
            for y in range(y0, y1):
                for z in range(z0, z1):
                    filled[(x, y, z)] = part
    verts, index, quads, parts = [], {}, [], []

    def vid(p):
        if p not in index:
            index[p] = len(verts)
            verts.append(p)
        return index[p]

    # Per axis and direction: the unit face of cube c on side (axis, +1 or -1), corners counter-clockwise
    # seen from outside.
    for c in sorted(filled):
        x, y, z = c
        for axis in range(3):
            for sgn in (1, -1):
                n = list(c)
                n[axis] += sgn
                if tuple(n) in filled:
                    continue
                u, v = (axis + 1) % 3, (axis + 2) % 3
                base = list(c)
                if sgn > 0:
                    base[axis] += 1
                corners = []
                for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = list(base)
                    p[u] += du
                    p[v] += dv
                    corners.append(tuple(p))
                if sgn < 0:
                    corners.reverse()
                quads.append([vid(p) for p in corners])
                parts.append(filled[c])
    return verts, quads, parts


def quat_axis_angle(axis, degrees):
    a = math.radians(degrees) / 2
    n = math.sqrt(sum(c * c for c in axis))
    return [axis[0] / n * math.sin(a), axis[1] / n * math.sin(a), axis[2] / n * math.sin(a), math.cos(a)]


def write_gltf(path, verts, quads, bones, weights_of, clips):
    """bones: list of (name, parent index or -1, global position). weights_of(grid point) → {bone index: w}."""
    positions = [tuple(c * H for c in p) for p in verts]
    indices = []
    for q in quads:
        indices += [q[0], q[1], q[2], q[0], q[2], q[3]]
    joints, weights = [], []
    for p in verts:
        w = sorted(weights_of(p).items(), key=lambda kv: (-kv[1], kv[0]))[:4]
        w += [(0, 0.0)] * (4 - len(w))
        joints.append([j for j, _ in w])
        weights.append([x for _, x in w])
    blob = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, comp, typ, target=None, minmax=None):
        while len(blob) % 4:
            blob.append(0)
        off = len(blob)
        raw = b"".join(struct.pack("<" + fmt, *item) if isinstance(item, (list, tuple)) else struct.pack("<" + fmt, item)
                       for item in data)
        blob.extend(raw)
        view = {"buffer": 0, "byteOffset": off, "byteLength": len(raw)}
        if target:
            view["target"] = target
        views.append(view)
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    a_pos = add(positions, "3f", len(positions), 5126, "VEC3", 34962, (lo, hi))
    a_idx = add(indices, "I", len(indices), 5125, "SCALAR", 34963)
    a_jnt = add(joints, "4B", len(joints), 5121, "VEC4", 34962)
    a_wgt = add(weights, "4f", len(weights), 5126, "VEC4", 34962)
    inv_bind = []
    for _, _, g in bones:
        inv_bind.append([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -g[0], -g[1], -g[2], 1])  # column-major
    a_ibm = add(inv_bind, "16f", len(inv_bind), 5126, "MAT4")
    nodes = [{"name": "body", "mesh": 0, "skin": 0}]
    for i, (name, parent, g) in enumerate(bones):
        pg = bones[parent][2] if parent >= 0 else (0.0, 0.0, 0.0)
        node = {"name": name, "translation": [round(g[k] - pg[k], 6) for k in range(3)]}
        children = [1 + j for j, (_, p, _) in enumerate(bones) if p == i]
        if children:
            node["children"] = children
        nodes.append(node)
    animations = []
    for clip_name, channels in clips:
        samplers, chans = [], []
        for bone, times, quats in channels:
            a_t = add(times, "f", len(times), 5126, "SCALAR", None, ([min(times)], [max(times)]))
            a_q = add(quats, "4f", len(quats), 5126, "VEC4")
            samplers.append({"input": a_t, "output": a_q, "interpolation": "LINEAR"})
            node = 1 + [b[0] for b in bones].index(bone)
            chans.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": "rotation"}})
        animations.append({"name": clip_name, "samplers": samplers, "channels": chans})
    gltf = {
        "asset": {"version": "2.0", "generator": "spherechain tests/data/creature/make_creature.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": nodes,
        "meshes": [{"name": "body", "primitives": [{"attributes": {"POSITION": a_pos, "JOINTS_0": a_jnt,
                                                                    "WEIGHTS_0": a_wgt}, "indices": a_idx}]}],
        "skins": [{"joints": list(range(1, 1 + len(bones))), "inverseBindMatrices": a_ibm, "skeleton": 1}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    if animations:
        gltf["animations"] = animations
    with open(path, "w") as f:
        json.dump(gltf, f, separators=(",", ":"))
        f.write("\n")


def creature(path):
    boxes = [("trunk", (-3, 3), (8, 12), (-10, 10)),
             ("HindLeg_L", (1, 3), (0, 8), (-9, -7)), ("HindLeg_R", (-3, -1), (0, 8), (-9, -7)),
             ("ForeLeg_L", (1, 3), (0, 8), (7, 9)), ("ForeLeg_R", (-3, -1), (0, 8), (7, 9)),
             ("Tail", (-1, 1), (10, 12), (-16, -10))]
    verts, quads, parts = boxes_surface(boxes)
    bones = [("Spine", -1, (0.0, 1.0, 0.0)), ("Pelvis", 0, (0.0, 1.0, -0.8)), ("Chest", 0, (0.0, 1.0, 0.8)),
             ("Tail01", 1, (0.0, 1.1, -1.0)), ("Tail02", 3, (0.0, 1.1, -1.3))]
    legs = {}
    for name, parent, x, z in (("HindLeg_L", 1, 0.2, -0.8), ("HindLeg_R", 1, -0.2, -0.8),
                               ("ForeLeg_L", 2, 0.2, 0.8), ("ForeLeg_R", 2, -0.2, 0.8)):
        bones.append((name + "_01", parent, (x, 0.8, z)))
        bones.append((name + "_02", len(bones) - 1, (x, 0.4, z)))
        legs[name] = (len(bones) - 2, parent)
    idx = {b[0]: i for i, b in enumerate(bones)}

    def leg_at(x, z):
        for name, (x0, x1), _, (z0, z1) in boxes[1:5]:
            if x0 <= x <= x1 and z0 <= z <= z1:
                return name
        return None

    def weights_of(p):
        x, y, z = p
        leg = leg_at(x, z)
        if leg and y <= 8:
            first, parent = legs[leg]
            if y == 8:
                return {first: 0.5, parent: 0.5}
            return {first + 1 if y < 4 else first: 1.0}
        if z <= -10 and -1 <= x <= 1 and y >= 10:
            if z == -10:
                return {idx["Tail01"]: 0.5, idx["Pelvis"]: 0.5}
            return {idx["Tail02"] if z < -13 else idx["Tail01"]: 1.0}
        return {idx["Pelvis"] if z < -3 else idx["Chest"] if z > 3 else idx["Spine"]: 1.0}

    ident = [0.0, 0.0, 0.0, 1.0]
    cross = quat_axis_angle((0, 0, 1), -35)  # the left fore leg's foot towards -X, under the chest
    clips = [("cross", [("ForeLeg_L_01", [0.0, 0.5, 1.0], [ident, cross, ident])]),
             ("still", [("ForeLeg_L_01", [0.0, 1.0], [ident, ident])])]
    write_gltf(path, verts, quads, bones, weights_of, clips)
    counts = {}
    for part in parts:
        counts[part] = counts.get(part, 0) + 2
    return len(verts), 2 * len(quads), counts


def snake(path):
    verts, quads, _ = boxes_surface([("bar", (-1, 1), (0, 2), (-10, 10))])
    bones = [("Seg0", -1, (0.0, 0.1, -1.0)), ("Seg1", 0, (0.0, 0.1, -0.5)), ("Seg2", 1, (0.0, 0.1, 0.0)),
             ("Seg3", 2, (0.0, 0.1, 0.5))]

    def weights_of(p):
        return {min(3, max(0, (p[2] + 10) // 5)): 1.0}

    write_gltf(path, verts, quads, bones, weights_of, [])
    return len(verts), 2 * len(quads)


def figure(path):
    """A standing humanoid whose bones are named node0…node12 (no usable names, as some exporters write):
    legs x [0.1, 0.3) left / [-0.3, -0.1) right, y [0, 0.8), z [-0.1, 0.1); trunk x [-0.3, 0.3) y [0.8, 1.5);
    neck and head x [-0.1, 0.1) y [1.5, 1.9); the arms hang beside the trunk with a gap of one cube
    (x [0.4, 0.6) left / [-0.6, -0.4) right, y [0.7, 1.5)), joined to it at the shoulders by one cube
    (x [0.3, 0.4), y [1.3, 1.5)). The geometry segmentation takes the gap for the armpit's end and makes an
    implausible body of it (PLAUS-LIMB-BALANCE), and the rig's names say nothing, so `--segmentation auto`
    must take the bone tree."""
    boxes = [("trunk", (-3, 3), (8, 15), (-1, 1)), ("head", (-1, 1), (15, 19), (-1, 1)),
             ("leg_l", (1, 3), (0, 8), (-1, 1)), ("leg_r", (-3, -1), (0, 8), (-1, 1)),
             ("arm_l", (4, 6), (7, 15), (-1, 1)), ("arm_r", (-6, -4), (7, 15), (-1, 1)),
             ("shoulder_l", (3, 4), (13, 15), (-1, 1)), ("shoulder_r", (-4, -3), (13, 15), (-1, 1))]
    verts, quads, parts = boxes_surface(boxes)
    # (name, parent, global position): hips 0, spine 1, chest 2, neck 3, head 4, then each limb's two bones.
    bones = [("node0", -1, (0.0, 0.8, 0.0)), ("node1", 0, (0.0, 1.1, 0.0)), ("node2", 1, (0.0, 1.4, 0.0)),
             ("node3", 2, (0.0, 1.5, 0.0)), ("node4", 3, (0.0, 1.7, 0.0)),
             ("node5", 2, (0.35, 1.4, 0.0)), ("node6", 5, (0.5, 1.1, 0.0)),
             ("node7", 2, (-0.35, 1.4, 0.0)), ("node8", 7, (-0.5, 1.1, 0.0)),
             ("node9", 0, (0.2, 0.8, 0.0)), ("node10", 9, (0.2, 0.4, 0.0)),
             ("node11", 0, (-0.2, 0.8, 0.0)), ("node12", 11, (-0.2, 0.4, 0.0))]

    def weights_of(p):
        x, y, z = p
        if y <= 8 and 1 <= abs(x) <= 3:  # a leg (its top ring half the hips)
            first = 9 if x > 0 else 11
            if y == 8:
                return {first: 0.5, 0: 0.5}
            return {first + 1 if y < 4 else first: 1.0}
        if abs(x) > 3:  # an arm: the upper arm above y 1.1, the forearm below
            first = 5 if x > 0 else 7
            return {first + 1 if y < 11 else first: 1.0}
        if abs(x) == 3 and 13 <= y <= 15:  # where the shoulder cube meets the trunk: half arm, half chest
            return {5 if x > 0 else 7: 0.5, 2: 0.5}
        if y >= 15:
            return {4 if y > 16 else 3: 1.0}
        return {2 if y > 12 else 1 if y > 10 else 0: 1.0}

    ident = [0.0, 0.0, 0.0, 1.0]
    swing = quat_axis_angle((0, 0, 1), -15)  # the left arm swings in, its hand towards the hip
    clips = [("swing", [("node5", [0.0, 0.5, 1.0], [ident, swing, ident])])]
    write_gltf(path, verts, quads, bones, weights_of, clips)
    return len(verts), 2 * len(quads)

if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    v, t, counts = creature(os.path.join(here, "creature.gltf"))
    print("creature.gltf:", v, "vertices,", t, "triangles,", dict(sorted(counts.items())))
    v, t = snake(os.path.join(here, "snake.gltf"))
    print("snake.gltf:", v, "vertices,", t, "triangles")
    v, t = figure(os.path.join(here, "figure.gltf"))
    print("figure.gltf:", v, "vertices,", t, "triangles")
