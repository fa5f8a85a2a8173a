"""Gaze stabilisation on the benchmark's turning scenes: mLPLC2 with and without ``stabilise`` (issue 22).

Generates the pan and tilt scenes of ``mlplc2.benchmark.suite()`` in memory and counts, per scene,
the collision objects warned before contact (a warning target within 20 px, or one object width,
of the object's centre in some frame before its contact frame) and the frames with any warning.
A development check, not the benchmark's scoring (``mlplc2 benchmark``, docs/evaluation.md)::

    python benchmarks/stabilise_pan_tilt.py pan,tilt
"""
import sys, time, json
import numpy as np
import mlplc2
from mlplc2.benchmark import suite
from mlplc2.evaluation.truth import parse

cams = sys.argv[1].split(",") if len(sys.argv) > 1 else ["pan", "tilt"]
scenes = [s for s in suite() if s.camera in cams]
tot = {False: [0, 0, 0], True: [0, 0, 0]}
for sc in scenes:
    st = sc.generate()
    gt = st.to_ground_truth()
    objs = gt["objects"]
    for stab in (False, True):
        m = mlplc2.MLPLC2(fps=st.fps, stabilise=stab)
        t0 = time.perf_counter()
        outs = [m.step(f) for f in st.frames]
        dt = (time.perf_counter() - t0) / len(outs) * 1e3
        warned = 0; ncol = 0; false = 0
        truth = parse({"videos": {"x.mp4": gt}})["x.mp4"]
        for o in truth.objects:
            if o.kind != "collision":
                continue
            ncol += 1
            cf = o.contact_frame
            for out in outs:
                if out.frame >= cf: break
                if any(t.warning and o.in_track(out.frame) and abs(t.x - o.point_at(out.frame).x) < max(20, o.point_at(out.frame).width) and abs(t.y - o.point_at(out.frame).y) < max(20, o.point_at(out.frame).width) for t in out.targets):
                    warned += 1; lead = (cf - out.frame) / st.fps; break
        nwarn_frames = sum(1 for out in outs if out.warning)
        tot[stab][0] += warned; tot[stab][1] += ncol; tot[stab][2] += nwarn_frames
        print(f"{sc.name:20s} stab={stab!s:5s} warned {warned}/{ncol}  warning frames {nwarn_frames}/{len(outs)}  {dt:.1f} ms/frame", flush=True)
print(tot)
