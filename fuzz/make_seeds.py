#!/usr/bin/env python3
"""Writes the generated seeds of the importer and configuration fuzzers (fuzz/README.md); standard library only.

fuzz/data/body.obj — the fixed body of fuzz_import_makehuman and fuzz_bake_config: the standing figure of
  tests/data/creature/make_creature.py (figure(): legs, trunk, head, arms hanging beside the trunk, a union of
  cubes of 0.1 units, 1,014 vertices, 2,024 triangles) as an OBJ with a MakeHuman header and group `body`.
corpus/import_makehuman/figure.* — a MakeHuman rig for it (bones with MakeHuman's names, each head a joint
  listing the figure's vertices nearest the bone's position, the figure's weights per bone): `.mhskel` JSON,
  a NUL, `.mhw` JSON (the fuzzer's input layout); variants with no weights part and with tiny rigs.
corpus/bake_config/* — configurations (the guide's keys and values), some followed by a NUL and a region map
  of the figure (per vertex and per triangle, the paper's five regions and a creature's named layout).
corpus/import_obj/generated_* — small OBJ files written here: the figure, every face-corner form, negative
  indices, groups, comments, a MakeHuman header.
corpus/import_gltf/figure.glb — tests/data/creature/figure.gltf as binary glTF (its buffer in the BIN chunk).
corpus/import_assimp/generated_iqm.bin — a minimal IQM (assimp-testmodels has none under 100 KB).
Copied seeds: the repository's own test data (tests/data/creature, tests/data/implausible, tests/c_api) and
small files of Debian's assimp-testmodels (/usr/share/assimp/models, BSD-3-clause like assimp:
/usr/share/doc/assimp-testmodels/copyright), named after their source; an assimp seed starts with the byte
that picks its format in fuzz_import_assimp. ../shared/data is never copied (its README forbids it).

Run from anywhere: python3 fuzz/make_seeds.py (deterministic).
"""
import base64
import json
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tests", "data", "creature"))
import make_creature  # noqa: E402  (the figure's boxes, bones and weights)


def capture_figure():
    got = {}

    def capture(path, verts, quads, bones, weights_of, clips):
        got.update(verts=verts, quads=quads, bones=bones, weights_of=weights_of)

    saved = make_creature.write_gltf
    make_creature.write_gltf = capture
    try:
        make_creature.figure(None)
    finally:
        make_creature.write_gltf = saved
    return got


def write(rel, data):
    path = os.path.join(HERE, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 100_000, (rel, len(data))
    with open(path, "wb") as f:
        f.write(data)


def fmt(x):
    return ("%.4f" % x).rstrip("0").rstrip(".") or "0"


def figure_obj(fig):
    lines = ["# basemesh fuzz-figure (fuzz/make_seeds.py: tests/data/creature figure(), units of 0.1)", "g body"]
    lines += ["v %s %s %s" % tuple(fmt(c * make_creature.H) for c in p) for p in fig["verts"]]
    lines += ["f %d %d %d %d" % tuple(i + 1 for i in q) for q in fig["quads"]]
    return "\n".join(lines) + "\n"


# The figure's bones (make_creature.figure: node0..node12) under MakeHuman's names.
MH_NAMES = ["root", "spine02", "spine01", "neck01", "head", "upperarm01.L", "lowerarm01.L", "upperarm01.R",
            "lowerarm01.R", "upperleg01.L", "lowerleg01.L", "upperleg01.R", "lowerleg01.R"]


def figure_rig(fig, bones_kept=None):
    verts, bones = fig["verts"], fig["bones"]
    keep = list(range(len(bones))) if bones_kept is None else bones_kept
    skel = {"name": "fuzz figure", "version": 110, "weights_file": "input.mhw", "bones": {}, "joints": {}}
    for b in keep:
        _, parent, g = bones[b]
        grid = tuple(round(c / make_creature.H) for c in g)
        near = sorted(range(len(verts)), key=lambda v: (sum((verts[v][k] - grid[k]) ** 2 for k in range(3)), v))[:4]
        joint = MH_NAMES[b] + "____head"
        skel["joints"][joint] = near
        bone = {"head": joint, "parent": MH_NAMES[parent] if parent in keep else None, "reference": None}
        skel["bones"][MH_NAMES[b]] = bone
    weights = {}
    for v, p in enumerate(verts):
        for b, w in sorted(fig["weights_of"](p).items()):
            if b in keep:
                weights.setdefault(MH_NAMES[b], []).append([v, round(w, 3)])
    mhw = {"name": "fuzz figure weights", "version": 110, "weights": weights}
    return json.dumps(skel, separators=(",", ":")), json.dumps(mhw, separators=(",", ":"))


# The figure's regions per vertex (paper five: 0 left arm, 1 right arm, 2 left leg, 3 right leg, 4 torso).
def paper_region(p):
    x, y, _ = p
    if abs(x) > 3:
        return 0 if x > 0 else 1
    if y < 8 and 1 <= abs(x) <= 3:
        return 2 if x > 0 else 3
    return 4


def region_maps(fig):
    verts, quads = fig["verts"], fig["quads"]
    per_vertex = [paper_region(p) for p in verts]
    tri = []
    for q in quads:
        r = min((per_vertex[i] for i in q if per_vertex[i] != 4), default=4)
        tri += [r, r]
    names = ["arm_L", "arm_R", "leg_L", "leg_R", "trunk"]
    return {
        "vertex_paper": json.dumps({"vertex_regions": per_vertex}, separators=(",", ":")),
        "triangle_symbols": json.dumps({"triangle_regions": ["R%d" % r for r in tri]}, separators=(",", ":")),
        "creature_names": json.dumps({"regions": names, "vertex_regions": [names[r] for r in per_vertex]},
                                     separators=(",", ":")),
        "paper_names": json.dumps({"vertex_regions": [["left_arm", "right_arm", "left_leg", "right_leg", "torso"][r]
                                                      for r in per_vertex]}, separators=(",", ":")),
    }


CONFIGS = {
    "empty": {},
    "guide_example": {"segmentation": "auto", "regions": "extended", "max_spheres": 128, "contact_margin_rel": 0.004,
                      "chains": [{"name": "zeta0", "members": ["R0", "R4L", "R2"]}]},
    "paper_fit": {"fit": "paper", "regions": "paper", "rays": 16, "spheres_per_level": 2, "disk_step_rel": 0.05,
                  "penetration_depth": 0.3},
    "cover_all_keys": {"fit": "cover", "max_spheres": 16, "cover_voxel_rel": 0.02, "cover_max_voxels": 5000,
                       "min_radius_rel": 0.003, "min_gain": 0.0002, "region_balance": 0.5, "refine_sweeps": 1,
                       "dilation_rel": 0.003, "skin_spheres": 4, "skin_tolerance_rel": 0.01, "skin_min_vertices": 8,
                       "medial_min_rel": 0.001, "contact_margin_rel": 0.004, "fold_margin_rel": -1, "near_rel": 0.005,
                       "reach_rel": 0.003, "crease_rel": 0.03, "pivot_poses": 0, "pivot_pose_angle": 30,
                       "compare_segmentations": False, "vertices": "source"},
    "geometry_paper": {"segmentation": "geometry", "regions": "paper", "max_spheres": 8},
    "chains_custom": {"regions": "paper", "chains": [{"name": "arms", "members": ["R0", "R4T", "R1"]},
                                                     {"name": "legs", "members": ["left_leg", "R4D", "right_leg"]},
                                                     {"members": ["R4"]}]},
    "skeleton": {"segmentation": "skeleton"},
    "pivot_poses": {"pivot_poses": 2, "pivot_pose_angle": 20, "regions": "paper"},
}
MAPPED = {  # configuration → region map
    "map_vertex_paper": ({"segmentation": "map", "region_map": "map.json", "regions": "paper"}, "vertex_paper"),
    "map_triangle_symbols": ({"region_map": "map.json", "regions": "extended"}, "triangle_symbols"),
    "map_creature": ({"region_map": "map.json", "fold_margin_rel": 0.001}, "creature_names"),
    "map_paper_names_chains": ({"region_map": "map.json", "regions": "paper",
                                "chains": [{"name": "zeta0", "members": ["R0", "R4L", "R2"]}]}, "paper_names"),
}


def figure_glb():
    with open(os.path.join(ROOT, "tests", "data", "creature", "figure.gltf")) as f:
        gltf = json.load(f)
    uri = gltf["buffers"][0].pop("uri")
    blob = base64.b64decode(uri.split(",", 1)[1])
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    return (b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON" + text +
            struct.pack("<I", len(blob)) + b"BIN\0" + blob)


def iqm_tetra_body():
    """IQM v2: one mesh, four vertices (float3 positions), four triangles, one joint 'root' with blend data."""
    pos = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    tris = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    text = b"\0body\0root\0"
    hdr_size = 124
    ofs_text = hdr_size
    ofs_meshes = ofs_text + len(text)
    mesh = struct.pack("<6I", 1, 0, 0, len(pos), 0, len(tris))  # name, material, first/num vertex, first/num tri
    ofs_va = ofs_meshes + len(mesh)
    pos_data = b"".join(struct.pack("<3f", *p) for p in pos)
    bi_data = b"".join(struct.pack("<4B", 0, 0, 0, 0) for _ in pos)
    bw_data = b"".join(struct.pack("<4B", 255, 0, 0, 0) for _ in pos)
    va = []  # type, flags, format, size, offset
    data_ofs = ofs_va + 3 * 20
    arrays = [(0, 7, 3, pos_data), (4, 1, 4, bi_data), (5, 1, 4, bw_data)]  # POSITION float; BLENDINDEXES/WEIGHTS ubyte
    blobs = b""
    for typ, form, size, d in arrays:
        va.append(struct.pack("<5I", typ, 0, form, size, data_ofs + len(blobs)))
        blobs += d
    ofs_tri = data_ofs + len(blobs)
    tri_data = b"".join(struct.pack("<3I", *t) for t in tris)
    ofs_joints = ofs_tri + len(tri_data)
    joint = struct.pack("<2i", 6, -1) + struct.pack("<10f", 0, 0, 0, 0, 0, 0, 1, 1, 1, 1)
    size = ofs_joints + len(joint)
    header = b"INTERQUAKEMODEL\0" + struct.pack(
        "<27I", 2, size, 0, len(text), ofs_text, 1, ofs_meshes, len(arrays), len(pos), ofs_va, len(tris), ofs_tri, 0,
        1, ofs_joints, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
    assert len(header) == hdr_size
    return header + text + mesh + b"".join(va) + blobs + tri_data + joint


OBJ_SEEDS = {
    "corners": "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1 2/1 3/1\nf 1//1 3//1 4//1\n"
               "f 1/1/1 2/1/1 3/1/1 4/1/1\n",
    "negative": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -3 -1\n",
    "groups": "# basemesh hm08\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng helper-x\nf 1 2 4\ng body other\nf 1 2 3\n"
              "g joint-x\nf 2 3 4\n",
    "formats": "v +1.5e0 -2.25E+1 .5\nv 1. 0x1 1e-3\nv 3\t4\t5\r\nf 1 2 3 \no obj\ns off\nusemtl m\nl 1 2\np 1\n",
}


ASSIMP_MODELS = "/usr/share/assimp/models"
# fuzz_import_assimp's kFormats: the first byte of an input picks its format.
ASSIMP_FORMATS = ["fbx", "dae", "x", "blend", "3ds", "ply", "stl", "iqm", "smd", "md5mesh", "ms3d", "b3d"]
ASSIMP_SEEDS = ["FBX/box.fbx", "FBX/boxWithCompressedCTypeArray.FBX", "FBX/phong_cube.fbx", "FBX/global_settings.fbx",
                "FBX/cubes_with_names.fbx", "Collada/cube_triangulate.dae", "Collada/box_nested_animation.dae",
                "Collada/cube_UTF16LE.dae", "Collada/cube_tristrips.dae", "Collada/library_animation_clips.dae",
                "X/test_cube_text.x", "X/test_cube_binary.x", "X/test_cube_compressed.x", "X/test.x",
                "BLEND/BlenderDefault_250_Compressed.blend", "BLEND/MirroredCube_252.blend", "3DS/RotatingCube.3DS",
                "3DS/test1.3ds", "3DS/fels.3ds", "PLY/cube.ply", "PLY/cube_binary.ply", "PLY/cube_uv.ply",
                "STL/triangle.stl", "STL/sphereWithHole.stl", "STL/Spider_binary.stl", "SMD/triangle.smd",
                "MD5/SimpleCube.md5mesh", "MS3D/twospheres.ms3d", "B3D/WusonBlitz.b3d"]
GLTF_SEEDS = ["glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf", "glTF2/simple_skin/simple_skin.gltf",
              "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", "glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb",
              "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "glTF2/wrongTypes/badArray.gltf"]
OBJ_COPIES = ["OBJ/box.obj", "OBJ/number_formats.obj", "OBJ/concave_polygon.obj", "OBJ/box_longline.obj",
              "OBJ/testmixed.obj", "OBJ/regr_3429812.obj", "OBJ/box_without_lineending.obj"]


def read(path):
    with open(path, "rb") as f:
        return f.read()


def copy_seeds():
    repo = lambda *p: os.path.join(ROOT, *p)  # noqa: E731
    for name in ("creature.gltf", "figure.gltf", "snake.gltf"):
        write("corpus/import_gltf/repo_%s" % name, read(repo("tests", "data", "creature", name)))
    write("corpus/import_obj/repo_boxes.obj", read(repo("tests", "data", "implausible", "boxes.obj")))
    write("corpus/bake_config/repo_fast.json", read(repo("tests", "data", "implausible", "fast.json")))
    write("corpus/bake_config/repo_paper_fit.json", read(repo("tests", "c_api", "paper_fit.json")))
    if not os.path.isdir(ASSIMP_MODELS):
        print("assimp-testmodels not installed: its seeds are not copied")
        return
    for rel in ASSIMP_SEEDS:
        ext = rel.rsplit(".", 1)[1].lower()
        tag = bytes([ASSIMP_FORMATS.index(ext)])
        write("corpus/import_assimp/assimp_%s" % rel.replace("/", "_"), tag + read(os.path.join(ASSIMP_MODELS, rel)))
    for rel in GLTF_SEEDS:
        write("corpus/import_gltf/assimp_%s" % os.path.basename(rel), read(os.path.join(ASSIMP_MODELS, rel)))
    for rel in OBJ_COPIES:
        write("corpus/import_obj/assimp_%s" % os.path.basename(rel), read(os.path.join(ASSIMP_MODELS, rel)))


def main():
    copy_seeds()
    fig = capture_figure()
    body = figure_obj(fig)
    write("data/body.obj", body)
    write("corpus/import_obj/generated_figure.obj", body)
    for name, text in OBJ_SEEDS.items():
        write("corpus/import_obj/generated_%s.obj" % name, text)

    skel, mhw = figure_rig(fig)
    write("corpus/import_makehuman/figure.mh", skel + "\0" + mhw)
    write("corpus/import_makehuman/figure_no_weights_part.mh", skel)
    skel3, mhw3 = figure_rig(fig, [0, 1, 2])
    write("corpus/import_makehuman/figure_trunk_only.mh", skel3 + "\0" + mhw3)

    maps = region_maps(fig)
    for name, cfg in CONFIGS.items():
        write("corpus/bake_config/%s.json" % name, json.dumps(cfg, indent=1))
    for name, (cfg, m) in MAPPED.items():
        write("corpus/bake_config/%s.json" % name, json.dumps(cfg, indent=1) + "\0" + maps[m])

    write("corpus/import_gltf/figure.glb", figure_glb())
    write("corpus/import_assimp/generated_iqm.bin", bytes([7]) + iqm_tetra_body())


if __name__ == "__main__":
    main()
