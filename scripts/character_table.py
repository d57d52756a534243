#!/usr/bin/env python3
"""Bakes every character-like model of ../shared/data and Debian's assimp-testmodels with the
spherechain CLI and writes one table: for each model either what the bake made (segmentation, spheres
per region, chains, bind coverage, bake time; with --evaluate the proxy's recall on its animation) or
the precise reason it was refused. Each baked model also gets its PNG views (front and side) in OUT_DIR
— look at them.

Usage: scripts/character_table.py [--binary PATH] [--shared DIR] [--models DIR] [--out DIR]
                                  [--repeats N] [--evaluate] [--markdown PATH]
Only the standard library; the CLI does the work (PNG views need rsvg-convert, as for `bake --png`).
"""
import argparse
import json
import os
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# (label, path relative to its root, root: "shared" | "models", animations to evaluate: "clip" (the file's
# first clip) | "morph" (the character's default key poses) | a list of (name, extra `evaluate` arguments) |
# None). Character-like: a body with limbs — humans, the four-legged Wuson, a spider — in the formats the
# baker reads; cubes, vehicles, props, RiggedSimple (a skinned cylinder) and FBX/huesitos and
# FBX/animation_with_skeleton (a bending tube, two towers of boxes) are not characters and are left out.
WUSON_POSES = [os.path.join(REPO, "data", "poses", "Testwuson", p + ".json")
               for p in ("forelegs_crossed", "hindlegs_crossed", "hind_overreach", "head_to_foreleg", "tail_to_hindleg")]
MODELS = [
    ("MakeHuman (OBJ + .mhskel rig)", "makehuman/base.obj", "shared", "morph"),
    ("CesiumMan (glTF, skinned, walk)", "gltf/CesiumMan.gltf", "shared", "clip"),
    ("BCN_Epileptic (X, skinned, clip)", "X/BCN_Epileptic.X", "models", "clip"),
    ("human (Collada archive)", "Collada/human.zae", "models", None),
    ("HUMAN (Blender)", "BLEND/HUMAN.blend", "models", None),
    ("mrfixit (IQM)", "IQM/mrfixit.iqm", "models", None),
    ("Wuson (X, skinned, 3 clips)", "X/Testwuson.X", "models",
     [("Run", ["--clip", "Wuson_Run"]), ("Walk", ["--clip", "Wuson_Walk"]), ("legs crossing, 5 key poses", ["--morph"] + WUSON_POSES)]),
    ("Wuson (SMD)", "SMD/WusonSMD.smd", "models", None),
    ("Wuson (B3D)", "B3D/WusonBlitz.b3d", "models", None),
    ("Wuson (MS3D)", "MS3D/Wuson.ms3d", "models", None),
    ("Wuson (OBJ)", "OBJ/WusonOBJ.obj", "models", None),
    ("spider (OBJ)", "OBJ/spider.obj", "models", None),
    ("spider (FBX)", "FBX/spider.fbx", "models", None),
]


def run(cmd):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def last_error(text):
    lines = [l for l in text.splitlines() if l.startswith("error")]
    return lines[-1] if lines else (text.strip().splitlines() or ["(no message)"])[-1]


def bake(args, label, path, anim):
    stem = os.path.splitext(os.path.basename(path))[0] + "_" + os.path.splitext(path)[1][1:].lower()
    asset = os.path.join(args.out, stem + ".sphc")
    report = os.path.join(args.out, stem + ".json")
    png = os.path.join(args.out, stem + ".png")
    row = {"model": label, "file": path, "stem": stem}
    best_ms = None
    for k in range(args.repeats):
        cmd = [args.binary, "-q", "bake", path, "-o", asset, "--report", report]
        if k == 0:
            cmd += ["--png", png]
        t0 = time.perf_counter()
        p = run(cmd)
        wall = (time.perf_counter() - t0) * 1000.0
        if p.returncode != 0:
            row.update(result="refused", exit=p.returncode, reason=last_error(p.stderr + p.stdout))
            return row
        with open(report) as f:
            rep = json.load(f)
        ms = rep.get("timings_ms", {}).get("total", wall)
        best_ms = ms if best_ms is None else min(best_ms, ms)
    seg = rep.get("segmentation", {})
    regions = rep.get("regions", {})
    row.update(
        result="baked",
        vertices=rep.get("vertices"),
        triangles=rep.get("triangles"),
        segmentation=seg.get("method", "?"),
        agreement=(seg.get("agreement") or {}).get("triangle_fraction"),
        compared_with=seg.get("compared_with"),
        regions=len(regions),
        # The paper's five as "R0 19 R1 20 …"; a creature's named: "R0 Tail 11, R1 HindLeg_L 14, …".
        per_region=(" ".join("%s %d" % (v["symbol"], v["spheres"]) for v in sorted(regions.values(), key=lambda v: int(v["symbol"][1:])))
                    if "body" not in rep else
                    ", ".join("%s %s %d" % (v["symbol"], n, v["spheres"])
                              for n, v in sorted(regions.items(), key=lambda kv: int(kv[1]["symbol"][1:])))),
        spheres=rep.get("spheres") if isinstance(rep.get("spheres"), int) else len(rep.get("spheres", [])),
        chains=len(rep.get("chains", [])),
        coverage=(rep.get("coverage") or {}).get("coverage"),
        protrusion=(rep.get("coverage") or {}).get("protrusion"),
        bake_ms=best_ms,
        png=png,
    )
    if args.evaluate and anim:
        specs = [(anim, [])] if isinstance(anim, str) else anim
        row["evaluations"] = []
        for k, (name, extra) in enumerate(specs):
            ev_json = os.path.join(args.out, stem + (".eval.json" if k == 0 else ".eval%d.json" % k))
            p = run([args.binary, "-q", "evaluate", asset, "--mesh", path, "--json", ev_json] + extra)
            if p.returncode != 0:
                row["evaluations"].append({"animation": name, "error": last_error(p.stderr + p.stdout)})
                continue
            with open(ev_json) as f:
                summary = json.load(f)["summary"]
            s = summary["proxy"]
            row["evaluations"].append({"animation": name, "recall_m1": s["recall_m1"], "recall_m2": s["recall_m2"],
                                       "sphere_recall": s["sphere_recall_m2"],
                                       "region_pairs": summary.get("exact_region_pairs"),
                                       "false_alarm_frames": len(s["false_alarm_frames"])})
    return row


def pct(x):
    return "—" if x is None else "%.1f" % (100.0 * x)


def markdown(rows, args):
    out = ["| model | result | segmentation | spheres (per region) | chains | bind coverage % | bake ms | recall M1 / M2 / spheres % (FA frames) |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["result"] != "baked":
            out.append("| %s | refused (exit %s): %s | | | | | | |" % (r["model"], r.get("exit", "?"),
                                                                       r.get("reason", r["result"]).replace("|", "/")))
            continue
        rec = "—"
        evals = r.get("evaluations", [])
        if evals:
            parts = []
            for e in evals:
                name = "" if len(evals) == 1 else e["animation"] + ": "
                if "error" in e:
                    parts.append(name + "evaluate: " + e["error"].replace("|", "/"))
                elif e.get("region_pairs") == 0:
                    parts.append(name + "no contact in it, %d FA frames" % e["false_alarm_frames"])
                else:
                    parts.append(name + "%s / %s / %s (%d)" % (pct(e["recall_m1"]), pct(e["recall_m2"]), pct(e["sphere_recall"]),
                                                               e["false_alarm_frames"]))
            rec = "; ".join(parts)
        seg = r["segmentation"] + ("" if r["agreement"] is None else
                                   " (%s agrees on %.0f %% of triangles)" % (r["compared_with"], 100.0 * r["agreement"]))
        out.append("| %s | baked, %d vertices, %d triangles | %s | %d (%s) | %d | %s | %.0f | %s |" % (
            r["model"], r["vertices"], r["triangles"], seg, r["spheres"], r["per_region"], r["chains"],
            pct(r["coverage"]), r["bake_ms"], rec))
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.environ.get("SPHERECHAIN", os.path.join(REPO, "build/dev/cli/spherechain")),
                    help="spherechain CLI (env SPHERECHAIN; default build/dev/cli/spherechain)")
    ap.add_argument("--shared", default=os.path.join(REPO, "..", "shared", "data"), help="../shared/data")
    ap.add_argument("--models", default="/usr/share/assimp/models", help="Debian's assimp-testmodels")
    ap.add_argument("--out", default="/tmp/spherechain-characters", help="assets, reports and PNGs go here")
    ap.add_argument("--repeats", type=int, default=3, help="bakes per model; the time is the fastest (default 3)")
    ap.add_argument("--evaluate", action="store_true", help="also evaluate the animated ones (minutes)")
    ap.add_argument("--markdown", help="write the table here too (default: stdout only)")
    args = ap.parse_args()
    if not os.path.exists(args.binary):
        sys.exit("character_table: no spherechain CLI at %s (build it, or --binary)" % args.binary)
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for label, rel, root, anim in MODELS:
        path = os.path.join(args.shared if root == "shared" else args.models, rel)
        if not os.path.exists(path):
            print("character_table: skipped (not found): %s" % path, file=sys.stderr)
            continue
        rows.append(bake(args, label, path, anim))
        r = rows[-1]
        print("%-40s %s" % (label, r["result"] if r["result"] != "baked" else "baked in %.0f ms" % r["bake_ms"]),
              file=sys.stderr)
    with open(os.path.join(args.out, "characters.json"), "w") as f:
        json.dump(rows, f, indent=1)
    table = markdown(rows, args)
    sys.stdout.write(table)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(table)


if __name__ == "__main__":
    main()
