"""Assemble benchmarks/RESULTS.md from the per-topic RESULTS-*.md files.

Usage: ``python benchmarks/assemble_results.py``. Each topic file is written by
the benchmark of that topic (with its commands, machine and date); this page
concatenates them under one index so every result is in one place.
"""

from pathlib import Path

HERE = Path(__file__).resolve().parent
ORDER = ["core", "baselines", "evaluation", "scale", "front", "refine", "symmetry", "viz", "robustness",
         "robustness-trials", "collections", "scans", "partial", "reliability", "tests", "texture"]
TITLES = {
    "core": "Core dense pipeline on TOSCA (issue 2)",
    "baselines": "The paper's baselines vs spectral (issue 3)",
    "evaluation": "Evaluation, benchmark and the paper's experiments (issue 3)",
    "scale": "Scale and speed (issue 5)",
    "front": "Speed, old vs new side by side (issue 5)",
    "refine": "Speed of the ZoomOut refinement, old vs new (issue 5)",
    "symmetry": "Left/right mirror and refinement (issue 6)",
    "viz": "Pictures and report (issue 4)",
    "robustness": "Right maps on data nobody tuned for, against pyFM (issue 12)",
    "robustness-trials": "What was tried for the whole-map choice (issue 12)",
    "scans": "Scans as they come: point clouds, partial shapes, holes (issue 15)",
    "partial": "Partial shapes, case by case (issue 15)",
    "collections": "Shape collections: prepare once, batch on Dask (issue 13)",
    "reliability": "Reliability: interrupts, fuzzing, soak (issue 16)",
    "tests": "Tests that notice broken code: mutation runs (issue 17)",
    "texture": "Texture transfer through the precise map (issue 14)",
}


def main() -> None:
    parts = [p for p in ORDER if (HERE / f"RESULTS-{p}.md").exists()]
    out = ["# meshcorr benchmark results", "",
           "Every result below states the command that reproduces it, the machine and the date.",
           "This page is assembled by `python benchmarks/assemble_results.py` from the topic files:", ""]
    out += [f"- [{TITLES[p]}](RESULTS-{p}.md)" for p in parts]
    for p in parts:
        text = (HERE / f"RESULTS-{p}.md").read_text().strip()
        lines = text.split("\n")
        if lines and lines[0].startswith("#"):
            lines = lines[1:]
        out += ["", "---", "", f"## {TITLES[p]}", "", *[
            ("#" + l if l.startswith("#") else l) for l in lines]]
    (HERE / "RESULTS.md").write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
