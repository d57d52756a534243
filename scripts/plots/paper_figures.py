#!/usr/bin/python3
"""Draw the paper's figures (§6) and the proxy's recall per frame from the runs of paper_figures.sh.

    /usr/bin/python3 scripts/plots/paper_figures.py /tmp/spherechain-paper-figures --docs docs

Inputs in the run folder (each figure is skipped, saying so, when its inputs are absent):
  mh_paper.rays.csv              bake --ray-csv of the paper fit (sphere, labels, ray, ..., surface,
                                 phi1, phi1_adjusted, phi2: distances from the disk centre along the ray)
  mh_paper.play.json, mh.play.json   play --json (per frame detect_m1_us, detect_m2_us: min of --repeat runs)
  mh.eval.json, cm.eval.json, bcn.eval.json   evaluate --json (per frame exact_region_pairs,
                                 proxy_region_pairs_m2, false_alarms_m2)
"""
import argparse
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {"surface": "black", "phi1": "tab:blue", "phi1_adjusted": "tab:green", "phi2": "tab:red"}
NAMES = {"surface": "skin (ray hit)", "phi1": "φ1", "phi1_adjusted": "φ1' (adjusted)", "phi2": "φ2 (MEB)"}


def load_json(path):
    if not os.path.exists(path):
        print(f"  skipped: {path} not found", file=sys.stderr)
        return None
    with open(path) as f:
        return json.load(f)


def fig13(run, out):
    """Fig. 13: per torso sphere 0-7 (bottom-up, left to right), distance along each disk ray."""
    path = os.path.join(run, "mh_paper.rays.csv")
    if not os.path.exists(path):
        print(f"  fig13 skipped: {path} not found", file=sys.stderr)
        return False
    rows = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.setdefault(int(r["sphere"]), []).append(r)
    spheres = sorted(rows)[:8]
    fig, axes = plt.subplots(2, 4, figsize=(15, 6.5), sharey=True)
    for k, (ax, s) in enumerate(zip(axes.flat, spheres)):
        rs = rows[s]
        for key in ("surface", "phi1", "phi1_adjusted", "phi2"):
            xs = [int(r["ray"]) for r in rs if r[key] != ""]
            ys = [float(r[key]) for r in rs if r[key] != ""]
            style = dict(marker=".", linestyle="none", markersize=5) if key == "surface" else dict(linewidth=1.4)
            ax.plot(xs, ys, color=COLOURS[key], label=NAMES[key], **style)
        ax.set_title(f"torso sphere {k} (asset #{s}, {rs[0]['labels']})", fontsize=10)
        ax.set_xlabel("ray $r_i$ of the sphere's half disk")
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("distance from the disk centre\n(source units, dm)")
    axes.flat[0].legend(fontsize=8, loc="upper left")
    fig.suptitle("Fig. 13 regenerated — MakeHuman, paper fit ($N_s$ = 2, PD = 30 %): where each ray meets the "
                 "skin and leaves φ1, φ1', φ2\n(the sphere closer to the skin dots is the better approximation "
                 "along that ray; a ray with no dot leaves through an opening)", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return True


def fig15(run, out):
    """Figs. 15-16 (CPU): µs per frame of M1 and M2 over the 40-frame morph."""
    series = [("paper fit", load_json(os.path.join(run, "mh_paper.play.json")), "-"),
              ("cover fit (default)", load_json(os.path.join(run, "mh.play.json")), "--")]
    series = [s for s in series if s[1]]
    if not series:
        print("  fig15 skipped: no play JSON", file=sys.stderr)
        return False
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 4.8))
    for name, play, ls in series:
        frames = [f["frame"] for f in play["frames"]]
        n = play["frames"][0]["tests_m2"]
        ax.plot(frames, [f["detect_m1_us"] for f in play["frames"]], ls, color="tab:purple",
                label=f"M1 (chains), {name}: {play['frames'][0]['tests_m1']} tests")
        ax.plot(frames, [f["detect_m2_us"] for f in play["frames"]], ls, color="tab:orange",
                label=f"M2 (all spheres), {name}: {n} tests")
        ax2.plot(frames, [f["pairs_m1_raw"] for f in play["frames"]], ls, color="tab:purple", label=f"M1 raw, {name}")
        ax2.plot(frames, [f["pairs_m2"] for f in play["frames"]], ls, color="tab:orange", label=f"M2, {name}")
    ax.set_xlabel("frame of the MakeHuman morph")
    ax.set_ylabel("detect time per frame (µs, one core, min of 20 runs)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Figs. 15–16 regenerated (CPU): M1 vs M2 per frame")
    ax2.set_xlabel("frame of the MakeHuman morph")
    ax2.set_ylabel("overlapping sphere pairs reported")
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=8)
    ax2.set_title("overlaps per frame (M1 counts a pair once per chain)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return True


def recall(run, out):
    """Exact region pairs per frame, those M2 reports, and false alarms, for each character."""
    runs = [("MakeHuman morph", "mh.eval.json"), ("CesiumMan walk", "cm.eval.json"),
            ("BCN_Epileptic clip", "bcn.eval.json")]
    runs = [(name, load_json(os.path.join(run, f))) for name, f in runs]
    runs = [r for r in runs if r[1]]
    if not runs:
        print("  recall skipped: no evaluate JSON", file=sys.stderr)
        return False
    fig, axes = plt.subplots(len(runs), 1, figsize=(13, 3.2 * len(runs)), squeeze=False)
    for ax, (name, ev) in zip(axes[:, 0], runs):
        frames = [f["frame"] for f in ev["frames"]]
        exact = [len(f["exact_region_pairs"]) for f in ev["frames"]]
        found = [len(set(f["exact_region_pairs"]) & set(f["proxy_region_pairs_m2"])) for f in ev["frames"]]
        false = [len(f["false_alarms_m2"]) for f in ev["frames"]]
        ax.bar(frames, exact, color="lightgray", edgecolor="gray", label="region pairs in exact contact")
        ax.bar(frames, found, width=0.5, color="tab:green", label="… reported by the spheres (M2)")
        ax.bar(frames, [-x for x in false], width=0.5, color="tab:red", label="false alarms (below the axis)")
        s = ev["summary"]["proxy"]
        margin = (f" (contact margin {100 * ev['contact_margin_rel']:.1f} % of height)"
                  if "contact_margin_rel" in ev else "")
        ax.set_title(f"{name}: region recall M2 {100 * s['recall_m2']:.1f} %, sphere-pair recall "
                     f"{100 * s['sphere_recall_m2']:.1f} %, false-alarm frames {len(s['false_alarm_frames'])}"
                     + margin, fontsize=10)
        ax.set_xlabel("frame")
        ax.set_ylabel("region pairs")
        ax.axhline(0, color="black", linewidth=0.8)
        ax.grid(axis="y", alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="folder written by paper_figures.sh")
    ap.add_argument("--docs", default=os.path.join(os.path.dirname(__file__), "..", "..", "docs"),
                    help="where the PNGs go (default: docs/ in the repo)")
    a = ap.parse_args()
    if not os.path.isdir(a.run):
        sys.exit(f"error: run folder '{a.run}' not found (run scripts/plots/paper_figures.sh first)")
    os.makedirs(a.docs, exist_ok=True)
    wrote = []
    for fn, name in ((fig13, "fig13_rays.png"), (fig15, "fig15_m1_m2_cpu.png"), (recall, "recall_per_frame.png")):
        path = os.path.join(a.docs, name)
        if fn(a.run, path):
            wrote.append(path)
    for p in wrote:
        print("wrote", p)
    if not wrote:
        sys.exit("error: nothing to plot")


if __name__ == "__main__":
    main()
