"""LGMD1 and LGMD2 at their default parameters: peak potential, spikes and alarms.

Measures, for each model, on

* the six basic stimuli (``mlplc2.stimuli.basic``) and the paper's ``basic/*.avi``;
* physical constant-speed approaches (``mlplc2.stimuli.looming``): dark and bright, plain
  and procedural background, three speeds, 320x240, 30 fps, contact at 2 s (frame 60);
* the real clips (``../shared/data/real``, ``../shared/data/paper/uav``): first alarm,
  alarm frames before the labelled ``contact_frame``, alarms on the no-collision clip;

the peak response (membrane potential), its frame, the number of spiking frames, the
longest run (spikes counted over consecutive spiking frames, what the alarm counts: LGMD2
alarms at 8, LGMD1 at 5), the number of alarm (collision) frames and the first alarm frame.
Nothing here is tuned: every model runs at one parameter set for every input.

Usage::

    python benchmarks/lgmd_operating_point.py [--data ../shared/data] [--models lgmd1,lgmd2]
        [--skip-real] [--repeat-threshold 16] [--json out.json]

``--models`` also takes the published variants of :data:`VARIANTS` (``lgmd2-csharp``,
``lgmd1-unsigned``, ``lgmd1-csig1``, ``lgmd1-sun``).

Missing data folders are skipped. docs/model.md ("LGMD2 ...", "LGMD1 ...") quotes the
figures this prints.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from mlplc2 import stimuli
from mlplc2.io import read_video
from mlplc2.models.lgmd import LGMD1, LGMD2, LGMD1Params, LGMD2Params

#: name -> (class, parameter changes, C#-style frame interval). ``lgmd1`` and ``lgmd2`` are the
#: package defaults; the others are the published models as far as parameters express them
#: (docs/model.md, "LGMD2 ..." and "LGMD1 ...").
VARIANTS = {
    "lgmd1": (LGMD1, {}, False),
    "lgmd2": (LGMD2, {}, False),
    # theta_1 = 1 (Fu's C#) instead of the mLPLC2 authors' 0.5
    "lgmd2-theta1": (LGMD2, {"a_on": 1.0}, False),
    # Fu's C# lgmd2OpenSource: theta_1 = 1, and tau_i = 1000 / fps in integer arithmetic (33 ms at 30 fps)
    "lgmd2-csharp": (LGMD2, {"a_on": 1.0}, True),
    # the LGMD1 defaults before issue 24: magnitudes (not signed), Single's W_I = 0.6, C_sig = 1
    "lgmd1-unsigned": (LGMD1, {"signed": False, "w_i": 0.6, "c_sig": 1.0}, False),
    # the published network at the published normalisation, C_sig = 1 (saturates)
    "lgmd1-csig1": (LGMD1, {"c_sig": 1.0}, False),
    # C_sig = 1, W_I = 0.4, T_s = 0.86: the values of Sun et al.'s Python LGMD (Yue & Rind 2006)
    "lgmd1-sun": (LGMD1, {"c_sig": 1.0, "t_sp": 0.86}, False),
}


def build(name: str, fps: float, repeat=None):
    cls, changes, int_interval = VARIANTS[name]
    params = (LGMD1Params if cls is LGMD1 else LGMD2Params)(**changes)
    if int_interval:
        fps = 1000.0 / (1000 // int(round(fps)))
    return cls(fps=fps, params=params, repeat_threshold=repeat)


def summarise(model, frames, contact: float | None = None) -> dict:
    """Run ``model`` (reset first) over ``frames``; return the figures of one row."""
    model.reset()
    r, spikes, alarms = [], [], []
    run = longest = 0
    for o in model.run(frames):
        r.append(o.response)
        spikes.append(o.spike)
        alarms.append(o.collision)
        # spikes counted over consecutive spiking frames (LGMD2: 1-2 a frame; LGMD1: 1)
        run = run + model.state.get("spikes", 1) if o.spike else 0
        longest = max(longest, run)
    r = np.asarray(r)
    alarms = np.asarray(alarms, bool)
    first = int(np.argmax(alarms)) if alarms.any() else None
    row = dict(peak=round(float(r.max()), 3), peak_frame=int(r.argmax()), spike_frames=int(np.sum(spikes)),
               longest_run=longest, alarm_frames=int(alarms.sum()), first_alarm=first, frames=len(r))
    if contact is not None:
        before = alarms[:int(np.ceil(contact))]
        row["contact"] = contact
        row["alarm_before_contact"] = bool(before.any())
        row["lead_frames"] = None if first is None or first >= contact else round(contact - first, 1)
    return row


def fmt(row: dict) -> str:
    s = (f"peak {row['peak']:.3f} @{row['peak_frame']:>3}  spikes {row['spike_frames']:>3} run {row['longest_run']:>2}  "
         f"alarms {row['alarm_frames']:>3}/{row['frames']:<3} first {str(row['first_alarm']):>4}")
    if "contact" in row:
        s += f"  contact {row['contact']:g}  lead {row['lead_frames']}"
    return s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data"))
    ap.add_argument("--models", default="lgmd1,lgmd2", help=f"comma-separated, from {', '.join(VARIANTS)}")
    ap.add_argument("--skip-real", action="store_true")
    ap.add_argument("--repeat-threshold", type=float, default=None,
                    help="Model.repeat_threshold for the real clips (default None: off; mlplc2.models.base."
                         "REPEAT_THRESHOLD = 16 holds duplicated frames)")
    ap.add_argument("--trace", default=None, metavar="BASIC_NAME",
                    help="also print every frame's response and mean G (sum_g / N_cells) on this basic stimulus")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    names = a.models.split(",")
    unknown = [n for n in names if n not in VARIANTS]
    if unknown:
        ap.error(f"unknown model(s) {', '.join(unknown)}; choose from {', '.join(VARIANTS)}")
    out: dict = {}

    def report(section: str, label: str, frames, fps: float, contact=None, repeat=None) -> None:
        for name in names:
            row = summarise(build(name, fps, repeat), frames, contact)
            out.setdefault(section, {}).setdefault(label, {})[name] = row
            print(f"  {label:<30} {name:<12} {fmt(row)}")
        sys.stdout.flush()

    print("basic stimuli (mlplc2.stimuli.basic, 100x100, 50 frames)")
    for s in stimuli.BASIC_NAMES:
        st = stimuli.basic(s)
        report("basic", s, st.frames, st.fps)

    if a.trace:
        st = stimuli.basic(a.trace)
        for name in names:
            m = build(name, st.fps)
            cells = st.frames[0].size
            trace = [f"{i}:{o.response:.3f}/{m.state['sum_g'] / cells:.1f}" for i, o in enumerate(m.run(st.frames))]
            print(f"  trace {a.trace} {name} (frame:response/mean G)  " + " ".join(trace))

    basic_dir = Path(a.data) / "paper" / "basic"
    if basic_dir.is_dir():
        print("basic stimuli (paper files)")
        for p in sorted(basic_dir.glob("*.avi")):
            frames, fps = read_video(p)
            report("basic_avi", p.name, frames, fps)

    print("physical approaches (stimuli.looming, 320x240, 0.5 m half-size, contact at 2 s = frame 60)")
    for polarity in ("dark", "bright"):
        for bg in ("plain", "procedural"):
            for speed in (2.0, 5.0, 10.0):
                st = stimuli.looming(polarity=polarity, background=bg, speed=speed, contact_time=2.0)
                c = st.objects[0].contact_frame
                report("looming", f"{polarity} {bg} v={speed:g}", st.frames, st.fps, c)

    print("frame size (stimuli.looming dark, plain, v=5: the same approach at three resolutions)")
    for size in ((160, 120), (320, 240), (640, 480)):
        st = stimuli.looming(size=size, polarity="dark", speed=5.0, contact_time=2.0)
        for name in names:
            m = build(name, st.fps)
            first, mean_g = None, []
            for i, o in enumerate(m.run(st.frames)):
                mean_g.append(m.state["sum_g"] / st.frames[0].size)
                if o.collision and first is None:
                    first = i
            out.setdefault("size", {}).setdefault(f"{size[0]}x{size[1]}", {})[name] = dict(
                first_alarm=first, mean_g_30=round(mean_g[30], 2))
            print(f"  {size[0]}x{size[1]:<26} {name:<12} first alarm {first}  mean G at frame 30 {mean_g[30]:.2f}")

    if not a.skip_real:
        truth_path = Path(a.data) / "real" / "ground_truth.json"
        if truth_path.exists():
            print(f"real clips (contact = labelled contact_frame; repeat_threshold {a.repeat_threshold})")
            clips = json.loads(truth_path.read_text())["clips"]
            for key, entry in clips.items():
                base = Path(a.data) / ("paper" if key.startswith("uav/") else "real")
                path = base / key
                if not path.exists():
                    continue
                frames, fps = read_video(path)
                report("real", key, frames, fps, entry.get("contact_frame"), a.repeat_threshold)
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    sys.exit(main())
