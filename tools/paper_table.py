#!/usr/bin/env python3
"""The paper scenes' edge strains next to Schreck et al.'s tables IV and V.

    for s in paper_cylinder_then_bend paper_mobius_strip paper_unload paper_crumple \\
             paper_first_singularity paper_preset_crease; do
        developable_sim run config/scenes/$s.yaml --stats $s.json
    done
    python3 tools/paper_table.py paper_*.json

Prints one markdown row per stats file. Table IV gives, per figure, c_mean (the mean
compression of S_P's edges against the pattern, %) and n_comp (the share of edges
compressed by more than 1 %) averaged "over all the animation frames" (sec. 7.3), so
the like-for-like numbers are `edge_strain.time_mean`; the final frame, the largest
|strain| in any frame and the share of edges over 1 % either way (stretch too, which
table IV does not count) are printed beside them. Table V's N_s is the largest number
of interior singular vertices; ours is `singular_points_max`.
"""
import json
import sys

# scene: (figure, table IV c_mean %, n_comp %, table V N_s)
PAPER = {
    "paper_cylinder_then_bend": ("fig. 1", 0.89, 8.0, 2),
    "paper_mobius_strip": ("fig. 18 top", 0.17, 0.1, 0),
    "paper_unload": ("fig. 18 bottom", 0.19, 2.0, 1),
    "paper_crumple": ("fig. 22, 2nd row", 1.47, 11.0, 15),
    "paper_first_singularity": ("fig. 17", None, None, None),
    "paper_preset_crease": ("fig. 22, 3rd row", None, None, None),
}


def row(path):
    d = json.load(open(path))
    scene = d["scene"]
    e = d["edge_strain"]
    mean, final, most = e["time_mean"], e["final"], e["max"]
    figure, c_mean, n_comp, n_s = PAPER.get(scene, ("", None, None, None))
    paper = "-" if c_mean is None else f"{c_mean:.2f} %, {n_comp:.1f} %"
    return (
        f"| {scene} ({figure}) "
        f"| {mean['compression_mean_pct']:.2f} %, {mean['compressed_edges_pct']:.1f} % "
        f"| {paper} "
        f"| {final['compression_mean_pct']:.2f} %, {final['compressed_edges_pct']:.1f} % "
        f"| {final['strained_edges_pct']:.1f} % ({most['strained_edges_pct']:.1f} %) "
        f"| {final['strain_max_pct']:.1f} % ({most['strain_max_pct']:.1f} %) "
        f"| {d['singular_points_max']} ({'-' if n_s is None else n_s}) |"
    )


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print(
        "| scene | c_mean, n_comp over all frames | table IV | the same, final frame "
        "| edges over 1 % either way, final (worst frame) | largest abs strain, final "
        "(any frame) | singular vertices (table V) |"
    )
    print("|---|---|---|---|---|---|---|")
    for p in paths:
        print(row(p))


if __name__ == "__main__":
    main(sys.argv[1:])
