"""Which committed tables does round-off change? (issue 13, item 4)

For each bundled scene with a stochastic record (figures/<scene>.toml), the record is
simulated with the excitation's rms scaled by 1, 1 + eps and 1 - eps (a round-off-sized
change on purpose), and its moments and peaks tables are written by the current code
(``nlbeam.app.scenes.outputs.write_table``) from each; the script prints, per table, the
rows and the cells that differ from the unperturbed one. The peaks are mapped onto an empty
diagram (the kinds of the scene's diagram are not compared: computing the 4-mode diagram
takes minutes); the peak selection, frequencies and errors are.

    python benchmarks/table_roundoff.py --scenes modal_beam paper_broadband --out /tmp/tr

Measured (session 13, 60 s records): the paper model's scenes give identical tables at
eps = 1e-13 (its record amplifies the change to 4e-11 of delta's std in 30 s); the 4-mode
beam's record becomes another realization (std 0.000511 / 0.000504 / 0.000516 +- 7e-6).
"""
import argparse
import csv
import os
import warnings
from types import SimpleNamespace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EMPTY = SimpleNamespace(branches=[], bifurcations=[], superharmonics=[])


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def _changed(a, b):
    """(changed cells, cells) between two CSV tables (rows compared in order)."""
    n = max(len(a), len(b))
    width = len(a[0])
    ch = sum(1 for i in range(1, n) for j in range(width)
             if i >= len(a) or i >= len(b) or a[i][j] != b[i][j])
    return ch, (n - 1) * width


def main():
    from nlbeam.app.scenes import load_scene
    from nlbeam.app.scenes.outputs import write_table
    from nlbeam.app.scenes.plan import plan
    from nlbeam.app.scenes.run import compute

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["modal_beam", "paper_broadband",
                                                      "paper_actuator"])
    ap.add_argument("--eps", type=float, default=1e-13)
    ap.add_argument("--out", default="table_roundoff_out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    factors = {"base": 1.0, "plus": 1.0 + a.eps, "minus": 1.0 - a.eps}
    for name in a.scenes:
        scene = load_scene(os.path.join(ROOT, "figures", f"{name}.toml"))
        tables = [d for d in scene.tables if d["kind"] in ("moments", "peaks")]
        for job in plan(scene, os.path.join(a.out, "cache")):
            if job.kind != "stochastic":
                continue
            label = next(v for v in scene.variants() if v[0] == job.variant)
            written = {}
            for tag, fac in factors.items():
                inputs = {**job.inputs, "stochastic": dict(job.inputs["stochastic"])}
                inputs["stochastic"]["rms"] = inputs["stochastic"]["rms"] * fac
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    res = compute(inputs)
                variants = [("", label[1], label[2], label[3], EMPTY, res,
                             {"periodic": "-", "stochastic": "-"})]
                for d in tables:
                    f = f"{name}{job.variant.replace('=', '')}_{d['kind']}_{tag}.csv"
                    written[(d["kind"], tag)] = write_table(dict(d, file=f), variants, a.out)
            for d in tables:
                base = _rows(written[(d["kind"], "base")])
                for tag in ("plus", "minus"):
                    other = _rows(written[(d["kind"], tag)])
                    ch, tot = _changed(base, other)
                    print(f"{name} {job.variant or '-'} {d['kind']:8s} base vs {tag}: rows "
                          f"{len(base) - 1} / {len(other) - 1}, changed cells {ch} of {tot}",
                          flush=True)


if __name__ == "__main__":
    main()
