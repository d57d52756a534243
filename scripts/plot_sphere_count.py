#!/usr/bin/python3
"""Plot bind coverage, protrusion and proxy recall against the sphere count (MakeHuman body).

Reads the point-*.json files written by scripts/plot_sphere_count.sh (one per bake: the cover fit at
several max_spheres budgets, and the paper fit as a reference) and writes a PNG and a CSV of the numbers.

    /usr/bin/python3 scripts/plot_sphere_count.py /tmp/spherechain-sphere-count \
        --png docs/sphere_count.png --csv docs/sphere_count.csv
"""
import argparse
import csv
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.transforms import blended_transform_factory  # noqa: E402

# The targets, in %: (key, target, "at least" when True / "at most" when False).
TARGETS = {
    "coverage": (90.0, True),
    "protrusion": (5.0, False),
    "recall_m2": (95.0, True),
    "sphere_recall_m2": (85.0, True),
}
SERIES = [  # key, legend label, colour, marker
    ("coverage", "bind coverage (% of body volume)", "tab:blue", "o"),
    ("protrusion", "protrusion (% of sphere volume outside the mesh)", "tab:orange", "s"),
    ("recall_m2", "proxy recall, region pairs M2 (%)", "tab:green", "^"),
    ("sphere_recall_m2", "proxy recall, sphere pairs M2 (%)", "tab:purple", "v"),
]
CSV_COLUMNS = [
    "label", "fit", "max_spheres", "spheres", "coverage_pct", "protrusion_pct", "outside_p95_pct_height",
    "outside_max_pct_height", "recall_m1_pct", "recall_m2_pct", "sphere_recall_m1_pct",
    "sphere_recall_m2_pct", "false_alarm_frames", "frames", "false_alarm_frame_list", "exact_region_pairs",
    "bake_ms", "bake_runs", "fit_ms", "contact_margin_rel", "false_alarm_margin_rel",
]


def load_point(path):
    p = json.load(open(path))
    s = p["summary"]
    bake = p["bake"]
    bind = s["bind_pose"]["phi1_adjusted"]
    fa = s["proxy"]["false_alarm_frames"]
    timings = bake.get("timings_ms") or {}
    return {
        "label": p["label"],
        "fit": bake.get("fit") or p["config"].get("fit", "cover"),
        "max_spheres": p["config"].get("max_spheres", "" if p["config"].get("fit") == "paper" else 128),
        "spheres": int(bake["spheres"]),
        "coverage_pct": 100.0 * s["coverage"]["phi1_adjusted"],
        "protrusion_pct": 100.0 * s["protrusion"]["phi1_adjusted"],
        "outside_p95_pct_height": 100.0 * bind["outside_p95_rel"],
        "outside_max_pct_height": 100.0 * bind["outside_max_rel"],
        "recall_m1_pct": 100.0 * s["proxy"]["recall_m1"],
        "recall_m2_pct": 100.0 * s["proxy"]["recall_m2"],
        "sphere_recall_m1_pct": 100.0 * s["proxy"]["sphere_recall_m1"],
        "sphere_recall_m2_pct": 100.0 * s["proxy"]["sphere_recall_m2"],
        "false_alarm_frames": len(fa),
        "frames": int(s["frames"]),
        "false_alarm_frame_list": " ".join(str(f) for f in fa),
        "exact_region_pairs": s.get("exact_region_pairs", ""),
        "bake_ms": p.get("bake_total_ms_min", timings.get("total", float("nan"))),
        "bake_runs": len(p.get("bake_total_ms_runs", [0])),
        "fit_ms": timings.get("fit", float("nan")),
        "contact_margin_rel": bake.get("contact_margin_rel", ""),
        "false_alarm_margin_rel": p["evaluate"].get("margin_rel", ""),
    }


def fmt(v, column=""):
    if isinstance(v, float):
        return f"{v:g}" if column.endswith("_rel") else f"{v:.1f}" if column.endswith("_ms") else f"{v:.2f}"
    return str(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("points_dir", help="folder with the point-*.json files of plot_sphere_count.sh")
    ap.add_argument("--png", default="docs/sphere_count.png")
    ap.add_argument("--csv", default="docs/sphere_count.csv")
    args = ap.parse_args()

    files = sorted(glob.glob(os.path.join(args.points_dir, "point-*.json")))
    if not files:
        sys.exit(f"error: no point-*.json in {args.points_dir} (run scripts/plot_sphere_count.sh first)")
    points = [load_point(f) for f in files]
    cover = sorted((p for p in points if p["fit"] != "paper"), key=lambda p: (p["spheres"], str(p["max_spheres"])))
    paper = [p for p in points if p["fit"] == "paper"]
    frames = points[0]["frames"]

    for path in (args.png, args.csv):
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(CSV_COLUMNS)
        for p in cover + paper:
            w.writerow([fmt(p[c], c) for c in CSV_COLUMNS])

    fig, ax = plt.subplots(figsize=(10, 7.6), dpi=120)
    xs = [p["spheres"] for p in cover]
    for key, label, colour, marker in SERIES:
        ys = [p[key + "_pct"] for p in cover]
        ax.plot(xs, ys, marker=marker, color=colour, lw=2, ms=7, label=label, zorder=3)
        target, at_least = TARGETS[key]
        ax.axhline(target, color=colour, ls="--", lw=1.1, alpha=0.45, zorder=1)
        ax.annotate(f"target {'≥' if at_least else '≤'} {target:g} %", xy=(1.0, target),
                    xycoords=("axes fraction", "data"), xytext=(4, 0), textcoords="offset points",
                    va="center", ha="left", fontsize=8.5, color=colour)
        for p in paper:
            ax.plot(p["spheres"], p[key + "_pct"], marker="D", ms=11, mfc="none", mec=colour, mew=2,
                    ls="none", zorder=4)

    # Protrusion sits near the bottom: print its values above the points.
    white = dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.85)
    for p in cover:
        ax.annotate(f"{p['protrusion_pct']:.1f}", xy=(p["spheres"], p["protrusion_pct"]), xytext=(0, 9),
                    textcoords="offset points", ha="center", va="bottom", fontsize=8, color="tab:orange",
                    bbox=white)
    # The paper fit: its values right of its diamonds, and one label pointing at them.
    for p in paper:
        for key, _, colour, _ in SERIES:
            ax.annotate(f"{p[key + '_pct']:.1f}", xy=(p["spheres"], p[key + "_pct"]), xytext=(9, 0),
                        textcoords="offset points", ha="left", va="center", fontsize=8, color=colour,
                        bbox=white)
        ax.annotate(f"paper fit\n({p['spheres']} spheres)", xy=(p["spheres"], p["coverage_pct"]),
                    xytext=(p["spheres"] - 30, 44), textcoords="data", ha="center", va="center", fontsize=9,
                    color="0.25", arrowprops=dict(arrowstyle="->", color="0.5", lw=0.8))

    # Zoom on the small numbers (protrusion, and how far the spheres reach outside) in the empty band.
    inset = ax.inset_axes([0.47, 0.31, 0.5, 0.2])
    inset.plot(xs, [p["protrusion_pct"] for p in cover], marker="s", color="tab:orange", lw=1.6, ms=5)
    inset.plot(xs, [p["outside_p95_pct_height"] for p in cover], marker="x", color="tab:brown", lw=1.6, ms=6)
    inset.axhline(TARGETS["protrusion"][0], color="tab:orange", ls="--", lw=1, alpha=0.45)
    for p in paper:
        inset.plot(p["spheres"], p["protrusion_pct"], marker="D", ms=6, mfc="none", mec="tab:orange", mew=1.6)
        inset.plot(p["spheres"], p["outside_p95_pct_height"], marker="D", ms=6, mfc="none", mec="tab:brown",
                   mew=1.6)
    inset.set_xlim(min(xs) - 6, max(xs) + 6)
    inset.set_ylim(0, 5.6)
    inset.set_xticks(xs)
    inset.tick_params(labelsize=7.5)
    inset.grid(True, alpha=0.25)
    inset.set_title("zoom: protrusion (% of sphere volume, orange) and\n"
                    "outside p95 (distance, % of body height, brown)", fontsize=8, pad=3)

    # False-alarm frames: one row of numbers under the curves, at each point's x.
    row = blended_transform_factory(ax.transData, ax.transAxes)
    ax.text(0.01, 0.235, f"frames with a false alarm (M2, of {frames}):", transform=ax.transAxes, fontsize=9,
            color="tab:red", ha="left", va="bottom")
    for p in cover:
        ax.text(p["spheres"], 0.195, str(p["false_alarm_frames"]), transform=row, ha="center", va="center",
                fontsize=10, color="tab:red", fontweight="bold")
    for p in paper:
        ax.text(p["spheres"], 0.16, f"paper fit: {p['false_alarm_frames']}", transform=row, ha="center",
                va="center", fontsize=8.5, color="tab:red")

    ax.set_xlabel("spheres (actual count after the bake; cover fit at max_spheres = "
                  + ", ".join(str(p["max_spheres"]) for p in cover) + ")")
    ax.set_ylabel("%")
    ax.set_ylim(-3, 104)
    lo, hi = min(xs + [p["spheres"] for p in paper]), max(xs + [p["spheres"] for p in paper])
    pad = 0.06 * (hi - lo)
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_xticks(sorted(set(xs + [p["spheres"] for p in paper])))
    ax.grid(True, alpha=0.25)

    cm = points[0]["contact_margin_rel"]
    fam = points[0]["false_alarm_margin_rel"]
    ax.set_title(f"MakeHuman body: coverage, protrusion and proxy recall against the sphere count\n"
                 f"{frames}-frame morph, contact margin = asset default"
                 + (f" ({100 * float(cm):g} % of height)" if cm != "" else "")
                 + (f"; false alarm: no triangles within {100 * float(fam):g} % of height" if fam != "" else ""),
                 fontsize=11)

    handles, labels = ax.get_legend_handles_labels()
    if paper:
        handles.append(Line2D([], [], marker="D", ms=9, mfc="none", mec="0.3", mew=2, ls="none"))
        labels.append('paper fit ({"fit": "paper"}), same colours')
    handles.append(Line2D([], [], color="0.4", ls="--", lw=1.1, alpha=0.6))
    labels.append("issue's targets (dashed, series colour)")
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=9, frameon=False,
               bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(args.png)
    print(f"wrote {args.png} and {args.csv}")

    widths = [max(len(c), 6) for c in CSV_COLUMNS[:13]]
    print("  ".join(c.rjust(w) for c, w in zip(CSV_COLUMNS[:13], widths)))
    for p in cover + paper:
        print("  ".join(fmt(p[c], c).rjust(w) for c, w in zip(CSV_COLUMNS[:13], widths)))


if __name__ == "__main__":
    main()
