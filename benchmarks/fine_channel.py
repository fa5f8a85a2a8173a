"""The benchmark with the finer front-end channel (``Params.fine_scale``; docs/model.md, "A finer
channel for small objects"): the mLPLC2 model is built with ``fine_scale`` and
``fine_silent``, then :func:`mlplc2.benchmark.benchmark` runs as ``mlplc2 benchmark --workers 0``
would (in this process, so the parameters reach the models)::

    python benchmarks/fine_channel.py /tmp/fine --scale 0.5 --silent 1 --settings drone [--holdout 1]
    python benchmarks/fine_channel.py /tmp/fine_all --scale 0.5 --real ../shared/data/real

Copy the suite's ready scenes into ``OUT/scenes`` first to save generating them. ``--scale 0``
is the default model (the benchmark's own figures).
"""

from __future__ import annotations

import argparse

from mlplc2 import MLPLC2, Params
from mlplc2.benchmark import benchmark


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--scale", type=float, default=0.5, help="Params.fine_scale (0: off)")
    ap.add_argument("--silent", type=float, default=1.0, help="Params.fine_silent")
    ap.add_argument("--settings", default=None, help="comma-separated settings (default all)")
    ap.add_argument("--holdout", type=int, default=0)
    ap.add_argument("--real", default=None, help="folder of the labelled real clips (default none)")
    a = ap.parse_args()
    init = MLPLC2.__init__

    def with_fine(self, *args, params=None, **kw):
        params = (params or Params()).replace(fine_scale=a.scale, fine_silent=a.silent)
        init(self, *args, params=params, **kw)

    MLPLC2.__init__ = with_fine
    benchmark(a.out, models=["mlplc2"], workers=0, real=a.real, holdout=a.holdout, progress=False,
              settings=a.settings.split(",") if a.settings else None)


if __name__ == "__main__":
    main()
