"""``mlplc2 run`` (models on a video, an image folder or a camera; :func:`mlplc2.run`) and
``mlplc2 demo`` (:func:`mlplc2.runner.demo`), with their printed summaries.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import warnings
from pathlib import Path

from .._validation import InputError, InputValueError
from ..io.formats import STDIN
from ..models.base import MAX_REPEATS, REPEAT_THRESHOLD, WORK_WIDTH, available_models, resolve_names
from .common import (EXIT_INTERRUPTED, EXIT_OK, EXIT_TRUNCATED, PROG, Subcommand, add_repeat_options,
                     add_warning_options, compile_notice, frame_size, hfov_degrees, nonneg_int, point_xy, pos_float,
                     pos_int,
                     repeat_threshold_option, say,
                     target_options, warn)



class _Once(argparse.Action):
    """An option that takes one value: given twice, an error (``--jsonl - --jsonl FILE`` kept the last
    silently, and nothing came on stdout)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if getattr(namespace, self.dest, None) is not None:
            raise argparse.ArgumentError(self, "given twice: it writes one stream (for a file and stdout: "
                                               "--jsonl - | tee FILE)")
        setattr(namespace, self.dest, values)


def _add_run(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", help="video file (AVI, MP4, ...), folder of images, glob pattern "
                                  "('frames/*.png', quoted), camera index (0, 1, ...), stream URL "
                                  "(rtsp://..., http(s)://...) or - (a video piped to standard input)")
    p.add_argument("--model", "-m", action="append", metavar="NAME",
                   help=f"model(s) to run, repeatable or comma-separated; one of "
                        f"{', '.join(available_models())} (default: mlplc2)")
    p.add_argument("--out", "-o", metavar="DIR",
                   help="output folder (default: <stem>_mlplc2/ next to the input)")
    p.add_argument("--fps", type=pos_float, metavar="F",
                   help="frame rate to assume (default: the video's; images: 30)")
    p.add_argument("--params", metavar="FILE.json",
                   help="JSON object of Params fields overriding the defaults, with {\"lgmd2\": {...}} sections for "
                        "other models (the format of 'mlplc2 batch --params'; 'mlplc2 params' lists the fields)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--resize", type=frame_size, metavar="WxH",
                      help="resize frames before the models (e.g. 320x240; not needed for size: wider frames "
                           "are reduced to 320 px, keeping their shape); coordinates in the outputs stay in input "
                           "pixels")
    size.add_argument("--scale", type=pos_float, metavar="S", help="resize by a factor (e.g. 0.5)")
    p.add_argument("--start", type=nonneg_int, default=0, metavar="N", help="first frame (0-based)")
    p.add_argument("--end", type=nonneg_int, metavar="N", help="stop before this frame")
    p.add_argument("--video", action="store_true", help="also write annotated.mp4 with the targets drawn")
    fields = p.add_mutually_exclusive_group()
    fields.add_argument("--fields", action="store_true",
                        help="with --video: also draw the attention fields that respond or alarm (by default "
                             "the video shows the targets only)")
    fields.add_argument("--all-fields", action="store_true",
                        help="with --video: also draw every attention field")
    p.add_argument("--hfov", type=hfov_degrees, metavar="DEG",
                   help="camera's horizontal field of view in degrees: targets get bearings (azimuth_deg, "
                        "elevation_deg; empty without it), and gaze stabilisation turns image motion into the "
                        "camera's rotation through it (60 assumed without it; --gyro needs it), so the warnings "
                        "depend on it: the defaults were set at 60, the benchmark scenes' value, and on the real "
                        "clips 78 warns 5 of 8 collisions where 60 warns 8 (docs/cli.md, --hfov). Give the true "
                        "value when known")
    p.add_argument("--heading", type=point_xy, metavar="X,Y",
                   help="a fixed heading: the point the camera moves towards (the focus of expansion), in the "
                        "pixels of the input (as every output, whatever --resize and the models' working size; "
                        "e.g. the frame's centre ((W-1)/2,(H-1)/2) for a camera that drives along its optical "
                        "axis); the targets' course (miss) and the camera-motion estimate use it; default: "
                        "measured from the images while the camera translates (with --stabilise), else the "
                        "frame's centre (TargetParams.heading; docs/targets.md); a negative X too: --heading -5,10")
    p.add_argument("--stabilise", action=argparse.BooleanOptionalAction, default=None,
                   help="gaze stabilisation (mlplc2, slplc2, lplc2): the camera's rotation is estimated every frame "
                        "and compensated before the front end, for a camera that pans, tilts or rolls "
                        "(docs/model.md, 'Camera motion'); on by default; --no-stabilise: the paper's model")
    p.add_argument("--gyro", metavar="FILE.csv",
                   help="the camera's angular velocity: a CSV with columns t (s, the video's clock), wx, wy, wz "
                        "(rad/s about the camera's x right, y down, z forward axes), interpolated at each frame "
                        "and used instead of the estimated rotation by the models that stabilise; needs --hfov "
                        "(docs/robot.md)")
    p.add_argument("--decoder", choices=("opencv", "pyav"), default="opencv",
                   help="video decoder (default: opencv)")
    p.add_argument("--backend", dest="decoder", choices=("opencv", "pyav"), default=argparse.SUPPRESS,
                   help=argparse.SUPPRESS)  # the old name of --decoder, kept for old command lines
    add_repeat_options(p, f"hold the models' output on duplicated frames: frames in which no pixel "
                          f"changed by more than {REPEAT_THRESHOLD:g} grey levels (--repeat-level) since the "
                          f"last processed one, at most {MAX_REPEATS} in a row; for videos whose frames were "
                          f"repeated to raise the frame rate (docs/model.md)")
    add_warning_options(p)
    p.add_argument("--jsonl", metavar="PATH|-", action=_Once,
                   help="also write one JSON line per frame (targets, warning, skipped frames; docs/robot.md) "
                        "to PATH or, with -, to standard output (everything else then goes to stderr), "
                        "flushed as each frame is done")
    p.add_argument("--live", action=argparse.BooleanOptionalAction, default=None,
                   help="when the models fall behind, take the newest frame and skip the others (counted); "
                        "default: on for cameras and rtsp:// (and other real-time) URLs, off for files, "
                        "http(s):// and -")
    p.add_argument("--max-frames", type=pos_int, metavar="N", help="stop after N frames")
    p.add_argument("--duration", type=pos_float, metavar="S", help="stop after S seconds (wall clock)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")


def _cmd_run(args) -> int:
    if args.jsonl != "-":
        return _run(args, args.jsonl)
    lines = sys.stdout
    with contextlib.redirect_stdout(sys.stderr):  # stdout carries the JSON lines alone
        return _run(args, lines)


def _run(args, jsonl) -> int:
    from ..runner import RunInterrupted, TruncatedInputWarning, damaged_message, run

    models = resolve_names(args.model or ["mlplc2"], what="--model")
    resize = args.resize
    if args.end is not None and args.end <= args.start:
        raise InputValueError(f"--end ({args.end}) must be larger than --start ({args.start})")
    if (args.fields or args.all_fields) and not args.video:
        flag = "--all-fields" if args.all_fields else "--fields"
        raise InputValueError(f"{flag} draws on annotated.mp4: give --video too")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TruncatedInputWarning)  # reported below as one line
        try:
            stabilise = {} if args.stabilise is None else {"stabilise": args.stabilise}   # None: the runner's default
            with compile_notice(models, args.quiet):
                result = run(args.source, models, out=args.out, fps=args.fps, resize=resize, scale=args.scale,
                             start=args.start, end=args.end, video=args.video, quiet=args.quiet,
                             hfov_deg=args.hfov, keep_rows=False, repeat_threshold=repeat_threshold_option(args),
                             decoder=args.decoder, draw_fields="all" if args.all_fields else "responding" if args.fields else "auto",
                             target_params=_target_params(args), jsonl=jsonl, live=args.live,
                             max_frames=args.max_frames, duration_s=args.duration, gyro=args.gyro,
                             params=_model_params(args.params, models), **stabilise)
        except RunInterrupted as exc:
            return _report_interrupt(exc)
        except InputError as exc:
            if args.gyro is None:
                raise
            raise type(exc)(_cli_names(str(exc))) from None
    _print_run_summary(args, result)
    if result.damaged:
        warn(damaged_message(result.source, result.damaged))
    if result.dropped or (result.message and not result.truncated):  # a dropped stream, a closed --jsonl pipe
        print(f"{PROG}: {result.message}", file=sys.stderr)
    elif result.truncated:
        warn(result.message)
        return EXIT_TRUNCATED
    return EXIT_OK


def _model_params(path, models: list[str]) -> dict | None:
    """``--params FILE.json`` as the run's ``params``: each model's parameter object where the file changes one of
    its parameters (:func:`mlplc2.batch.param_sets`, checked against every model of the run first; None: none)."""
    if path is None:
        return None
    from ..batch import model_params, param_sets

    pset = param_sets(path, None, models)[0]
    params = {m: model_params(pset, m) for m in models}
    if pset and all(p is None for p in params.values()):   # it changes parameters, but of none of these models
        warn(f"{path}: changes none of the parameters of {', '.join(models)} (its fields are other models'; "
             f"'mlplc2 params', with --lgmd2, --lgmd1 or --flow, lists them)")
    return {m: p for m, p in params.items() if p is not None} or None


def _target_params(args) -> dict | None:
    """The run's ``target_params``: the warning options and ``--heading`` (None: the defaults)."""
    options = target_options(args)
    if args.heading is not None:
        options["heading"] = args.heading
    return options or None


#: The keywords a model's gyro refusal names (Python) and this command's options for them.
_GYRO_KEYWORDS = {"stabilise=False": "--no-stabilise", "(hfov_deg)": "(--hfov)"}


def _cli_names(message: str) -> str:
    """``message`` with the Python keywords of a gyro refusal (``Model.gyro_refusal``) as this command's options."""
    for keyword, option in _GYRO_KEYWORDS.items():
        message = message.replace(keyword, option)
    return message


def _timing(result) -> str:
    """``in 12.3 s (32.5 frames/s)``: the wall time of a run's frame loop and its rate."""
    rate = result.n_frames / result.seconds if result.seconds > 0 else math.inf
    return f"in {result.seconds:.1f} s ({rate:.1f} frames/s)"


def _report_interrupt(exc) -> int:
    """One line for a run stopped by Ctrl-C or SIGTERM (``runner.RunInterrupted``)."""
    res = exc.result
    print(f"{PROG}: interrupted after {res.n_frames} frames; outputs for them are in {res.out}", file=sys.stderr)
    return EXIT_INTERRUPTED


#: :func:`_print_run_summary`'s note: frames narrower than this (px) are smaller than the defaults were set for (a new
#: user's trial, session 47: 160x120 copies of night_rear_end and sudden_turning_vehicle never warned)
SMALL_WIDTH = 240


def _print_run_summary(args, result) -> None:
    w, h = result.size
    mw, mh = result.model_size
    size = f"{w}x{h}" + (f" -> {mw}x{mh}" if (mw, mh) != (w, h) else "")
    source = "stdin" if result.source == STDIN else result.source   # as the progress bar says
    frames = f"{result.n_frames} frame{'' if result.n_frames == 1 else 's'}"
    lines = [f"{frames} of {source} ({size}, {result.fps:g} fps) {_timing(result)}"]
    turned = [n for n in result.models if result.stabilise.get(n)]
    if turned:                 # what fields.json's "stabilise" records: the paper's model is --no-stabilise
        lines.append(f"  gaze stabilised (the camera's rotation compensated): {', '.join(turned)}; "
                     f"--no-stabilise runs the paper's model")
    for name in result.models:
        fields = result.fields.get(name, [])
        if fields:
            alarms = [f for f in fields if f["first_alarm_frame"] is not None]
            lines.append(f"  {name}: {len(fields)} field(s), {len(alarms)} in alarm")
            # the six strongest of the fields that responded (a field with peak 0 never did)
            for f in sorted((f for f in fields if f["peak_response"] > 0), key=lambda f: -f["peak_response"])[:6]:
                alarm = f", alarm at frame {f['first_alarm_frame']}" if f["first_alarm_frame"] is not None else ""
                lines.append(f"    #{f['id']} at ({f['x']:.0f}, {f['y']:.0f}), frames {f['born']}-"
                             f"{'' if f['died'] is None else f['died']}, peak {f['peak_response']:.3g} "
                             f"at frame {f['peak_frame']}{alarm}")
        else:
            alarms = result.alarms[name]
            first = f", first alarm at frame {alarms['first']}" if alarms["first"] is not None else ", no alarm"
            peak = "" if alarms.get("peak") is None else f" (peak {alarms['peak']:.3g} at frame {alarms['peak_frame']})"
            lines.append(f"  {name}: no fields{first}{peak}")
        targets = result.target_summaries.get(name)
        if targets:
            warned = sorted((t for t in targets if t["first_warning_frame"] is not None),
                            key=lambda t: t["first_warning_frame"])
            lines.append(f"  {name}: {len(targets)} target(s), {len(warned)} warned"
                         + (f" (first warning at frame {warned[0]['first_warning_frame']})" if warned else ""))
            for t in warned[:6]:                 # which targets warned, where, how soon, on what course
                at = t["at_first_warning"] or {}
                ttc = ", no time to contact yet (the field alarm's warning)" if at.get("ttc_s") is None \
                    else f", time to contact {at['ttc_s']:.2f} s"
                miss = "" if at.get("miss") is None else f", miss {at['miss']:.2f} extents"
                runs = t.get("warning_runs") or [[t["first_warning_frame"], t["first_warning_frame"]]]
                spans = ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs[:4]) + (", ..." if len(runs) > 4 else "")
                lines.append(f"    T{t['id']} warned from frame {t['first_warning_frame']} on {t['warning_frames']} "
                             f"frame(s) ({spans}), at ({at.get('x', 0):.0f}, {at.get('y', 0):.0f}){ttc}{miss}")
    if result.skipped:
        lines.append(f"skipped {result.skipped} frame(s) of the live source: the models took the newest frame")
    held = max(result.repeated.values(), default=0)
    if held and not result.duplicated:  # --skip-repeats, --repeat-level, or found out in a stream (else: the note)
        lines.append(f"repeated frames: the models held their output on {held} of {result.n_frames} frames "
                     f"(--every-frame processes every frame)")
    if result.latency:
        lat = result.latency
        queued = Path(result.source).is_file()  # a file is decoded ahead: its frames wait in the queue
        lines.append(f"latency from decoding to results: median {lat['median_ms']:.1f} ms, "
                     f"99th percentile {lat['p99_ms']:.1f} ms, max {lat['max_ms']:.1f} ms"
                     + (" (a file: the wait in the decoding queue included; a live source has none)" if queued else ""))
    if result.out is not None:
        lines.append(f"outputs in {result.out}: {', '.join(sorted(result.files))}")
    say(args, *lines)
    if result.duplicated and not args.quiet:  # the decision of fields.json's "duplicated"
        print(f"{PROG}: note: the video repeats its frames (duplicated frames): the models held their output on "
              f"{held} of {result.n_frames} frames (--every-frame processes every frame)", file=sys.stderr)
    if result.n_frames == 1 and not args.quiet:  # valid, but "no fields, no alarm" would read as "nothing approaches"
        print(f"{PROG}: note: one frame only: the models respond to change between frames, so none could respond",
              file=sys.stderr)
    w, h = result.model_size
    if result.n_frames > 1 and 0 < w < SMALL_WIDTH and not args.quiet:
        print(f"{PROG}: note: the models saw {w}x{h} frames, narrower than the {WORK_WIDTH} px their defaults were set "
              f"and measured at: an object covers fewer pixels and its growth is measured less well, so a warning may "
              f"come late or not at all (docs/cli.md, --scale)", file=sys.stderr)


# ---------------------------------------------------------------------------
# demo
# ---------------------------------------------------------------------------
#: The note `mlplc2 demo` ends with (stderr): why it runs the paper's model, not ``mlplc2 run``'s stabilised one.
DEMO_NOTE = ("note: the paper's model, without gaze stabilisation (on by default in 'mlplc2 run'): the scene's "
             "background scrolls behind a still camera; --stabilise takes the scroll for a pan (docs/model.md)")
DEMO_NOTE_STABILISED = ("note: gaze stabilisation on: the scroll is taken for a pan, so the objects, which keep their "
                        "places in the image, drift with the camera; fields and alarms come later (docs/model.md)")


def _add_demo(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", "-o", default="mlplc2_demo", metavar="DIR",
                   help="folder for demo.mp4, its ground truth and the outputs (default: ./mlplc2_demo)")
    p.add_argument("--scene", choices=("four_phase", "six_objects"), default="four_phase",
                   help="which multi-object scene (default: four_phase, 400 frames)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar and no summary")
    p.add_argument("--stabilise", action="store_true",
                   help="gaze stabilisation, as 'mlplc2 run' has it by default (off here: the scene's background "
                        "scrolls behind a still camera; stabilised, the scroll is taken for a pan)")


def _cmd_demo(args) -> int:
    from ..runner import DEMO_MODELS, RunInterrupted, demo

    try:
        with compile_notice(list(DEMO_MODELS), args.quiet):
            d = demo(args.out, scene=args.scene, quiet=args.quiet, stabilise=args.stabilise)
    except RunInterrupted as exc:
        return _report_interrupt(exc)
    lines = [f"demo scene {d.video} ({d.result.n_frames} frames) with {', '.join(d.result.models)} "
             f"{_timing(d.result)}",
             "  object  centre        frames    mlplc2 field  centre        error   first alarm"]
    for m in d.matches:
        cx, cy = m["center"]
        t0, t1 = m["frames"]
        if m["field"] is None:
            lines.append(f"  {m['object']:>6}  ({cx:>3.0f}, {cy:>3.0f})  {t0:>3}-{t1:<4}  none")
            continue
        fx, fy = m["field_center"]
        alarm = "-" if m["first_alarm_frame"] is None else str(m["first_alarm_frame"])
        lines.append(f"  {m['object']:>6}  ({cx:>3.0f}, {cy:>3.0f})  {t0:>3}-{t1:<4}  #{m['field']:<11} "
                     f"({fx:>3.0f}, {fy:>3.0f})  {m['distance']:>5.1f}px  {alarm}")
    n_fields = len(d.result.fields.get("mlplc2", []))
    matched = {m["field"] for m in d.matches if m["field"] is not None}
    lines.append(f"  mlplc2 made {n_fields} field(s); {len(matched)} matched an object")
    lines.append(f"outputs in {d.result.out}: {', '.join(sorted(d.result.files))}")
    say(args, *lines)
    if not args.quiet:
        print(f"{PROG}: {DEMO_NOTE_STABILISED if args.stabilise else DEMO_NOTE}", file=sys.stderr)
    return EXIT_OK


RUN = Subcommand("run", "run models on a video, image folder, camera, stream URL or stdin (-); write CSV, "
                 "JSON, PNG (and MP4; --jsonl: a JSON line per frame)",
                 _add_run, _cmd_run)
DEMO = Subcommand("demo", "generate a multi-object scene, run the models on it, compare with the truth",
                  _add_demo, _cmd_demo)
