"""The target layer's parameters (:class:`TargetParams`): candidates and their box, the image
measurement, the time to contact and course fits, and the warning rule (``docs/targets.md``,
whose parameter table ``mlplc2 params --targets --markdown`` regenerates from the fields here).
"""

from __future__ import annotations

from dataclasses import dataclass

from .._validation import InputValueError, Valid, check_fields
from ..params import ParameterSet, document_parameters, param

__all__ = ["TargetParams"]


@document_parameters("Parameters")
@dataclass(frozen=True)
class TargetParams(ParameterSet):
    """Parameters of the target layer: candidates, the image measurement, time to contact,
    course and the warning (one set for every input; ``docs/targets.md``).

    Valid values (the table below; checked at construction; one-line
    :class:`mlplc2.InputError` otherwise, a ``ValueError`` or ``TypeError``):
    integers are Python or NumPy integers (not bools), stored as Python ints;
    numbers are finite Python or NumPy scalars (not bools, strings or arrays) within
    float32's range, stored as Python floats; ``heading`` is None or two numbers.
    """

    # --- candidates and their box ---------------------------------------------------------
    band: int = param(2, "Half-width of the strips along a seed's row and column (:func:`measure_extent`).",
                      unit="px", valid=Valid.integer(0))
    min_peak: float = param(0.08, "Smallest outward LM (profile mean, after the gain) that counts as an edge.",
                            valid=Valid.real(minimum=0))
    noise_k: float = param(3.0, """An edge complex must exceed ``noise_k`` x the 75th percentile of its
                           profile (noise floor).""", valid=Valid.real(minimum=0))
    rel_start: float = param(0.3, """An edge complex must reach ``rel_start`` x the largest value within
                             ``local`` px of its start.""", valid=Valid.real(minimum=0, maximum=1))
    local: int = param(20, "How far beyond the start of a complex a stronger edge is searched for (see ``rel_start``).",
                       unit="px", valid=Valid.integer(0))
    rel_edge: float = param(0.25, "Outer boundary of the edge complex: where it falls below ``rel_edge`` x its peak.",
                            valid=Valid.real(minimum=0, maximum=1))
    gap: int = param(6, "Lobes closer than this belong to one edge complex (fast edges make 2-3 lobes).",
                     unit="px", valid=Valid.integer(0))
    edge_offset: float = param(6.5, "How far the outer boundary of the LM lobes trails the true edge (added back).",
                               unit="px", valid=Valid.real(minimum=0))
    max_shift: float = param(40.0, """A candidate box whose centre lies further than this (in x or y) from
                             its seed point is dropped: it encloses two things, or background (40 = R_AF).""",
                             unit="px", valid=Valid.real(minimum=0))
    claim: float = param(12.0, """Margin around a target's box that belongs to it: no new candidate is
                         sought there (the front end's local motion spreads about r_Di = 11 px beyond a
                         moving edge).""", unit="px", valid=Valid.real(minimum=0))
    seed_lm: float = param(0.5, """Local motion (LM, Eq. 12) above which the strongest point outside every
                           target and attention field also seeds a candidate (one per nominal frame interval
                           since the last frame, at most ``change_frames``: a 7.5 fps frame seeds 4), far below
                           the field threshold T_a = 10: a far object grows by a fraction of a pixel per
                           frame. 0 = attention fields only.""", valid=Valid.real(minimum=0))
    seed_contrast: float = param(20.0, """... and above this many times the frame's mean LM (a salient
                                 point, not a moving background).""", valid=Valid.real(minimum=0))
    seed_change: float = param(6.0, """When no local motion stands out, the largest grey-level change over
                               the last ``change_frames`` frames outside every target and field seeds a
                               candidate (:meth:`TargetLayer._change_seed`) when it is at least this
                               much and ``seed_contrast`` times the frame's mean change. 0 = off.""",
                               unit="grey levels", valid=Valid.real(minimum=0))
    lm_seeds: int = param(2, """LM seeds (``seed_lm``, else ``seed_change``) per nominal frame interval: the strongest
                          point outside every target, field and seed tried before it (``claim``), that many
                          times; the seeds beyond the first are the extra seeds (``extra_change``, ``seed_focus``,
                          ``seed_shadow``), tried also when the first finds nothing (since session 37). 2 (the
                          default since session 18, with ``seed_shadow``: TTC coverage 69.3 -> 74.9 % on the
                          standard suite, up 3.4-8.0 points on each of holdouts 1-10 (71.7-81.6 %), no collision
                          lost: docs/history.md, "Shadow targets, session 18"); 1 = the strongest only (main's
                          before); 3 without ``seed_focus`` measured, not adopted ("Where TTC coverage is lost"; with
                          it, "A seed's own focus").""",
                          unit="seeds", valid=Valid.integer(1))
    seed_focus: float = param(0.25, """An extra LM seed (beyond the first per nominal frame interval:
                              ``lm_seeds`` > 1) becomes a
                              target only when its growth test's alignment (``change_frames``) expands about
                              a point within this many half-sizes of its box from its centre (its shift at
                              most the growth times that distance, plus ``focus_slack``) and its box is not
                              cut by the border (``border``): an object on a collision course expands about
                              a point inside itself, the static world seen from a translating camera about
                              the heading, outside a patch beside the path. 0.25 (the default since session 18,
                              with ``seed_shadow``: docs/history.md, "Shadow targets, session 18"); 0 = no test;
                              0.25-2 with ``lm_seeds`` 3 and LM extra seeds measured in session 15 ("A seed's own
                              focus").""", unit="half-sizes", valid=Valid.real(minimum=0))
    focus_slack: float = param(0.25, """The shift beyond its focus (``seed_focus``) a seed's alignment may have: the
                               alignment's own error.""", unit="px", valid=Valid.real(minimum=0))
    seed_shadow: bool = param(True, """A target born from an extra seed (``lm_seeds`` > 1) is a shadow until its
                              first time to contact: not output, it owns no attention field, claims no seed
                              but the extra seeds', counts against no ``max_targets``, is neither remembered
                              nor refound and yields to any other target over it, so that the extra seeds
                              change none of the other targets until one of theirs measures an approach; when
                              shown (that first time to contact) it is refound as a new target would be (a
                              target lost there lately gives it its id). On (the default since session 18, with
                              ``lm_seeds`` 2, ``extra_change`` 4, ``extra_window`` 48, ``seed_focus`` 0.25,
                              ``shadow_uniform``, ``merge_ttc`` 2: std and holdouts 1-10 measured, docs/history.md,
                              "Shadow targets, session 18"; session 17's measurement without the last two lost a
                              collider, "Shadow targets"). Off = an extra seed's target is output from its
                              birth.""", valid=Valid.boolean())
    extra_change: float = param(4.0, """The extra seeds of each nominal frame interval (``lm_seeds`` > 1) are change seeds
                                (``seed_change``) whose change is at least this many times the frame's mean change,
                                not LM seeds: a small object that grows at the heading changes its grey levels
                                where its LM is the frame's least. They are tried also on a frame whose first seed
                                finds nothing: until session 37 they were not, and a small object that grows
                                slowly where nothing else stands out got no seed at all (docs/history.md, "The extra
                                seeds when the first finds nothing"). 4 (the default since session 18, with
                                ``seed_shadow``; 4-5 measured in session 17: docs/history.md, "Shadow targets"); 0 = LM
                                seeds, as the first.""", unit="x mean change", valid=Valid.real(minimum=0))
    extra_window: float = param(48.0, """With ``extra_change``, an extra seed's change is measured against the mean change
                                of a window this wide around it, not the frame's: the seed goes where the grey
                                levels change most against their surround (at least ``seed_change`` grey levels
                                and ``extra_change`` times the surround's mean): a small object at the heading
                                over a quiet backdrop, not the near ground that changes everywhere. 48 (the
                                default since session 18; session 17 measured it against the frame's mean on the
                                traced misses: docs/history.md, "Shadow targets"); 0 = the frame's mean.""", unit="px", valid=Valid.real(minimum=0))
    shadow_uniform: bool = param(True, """With ``seed_shadow``, a shadow's box (an extra change seed's, the change it swept) is
                                 put on the uniform region at its centre each frame, as a box seeded on a uniform
                                 region (``uniform_reseat``, ``uniform_growth``), when that region is a compact
                                 object inside it of about its size: a dark square's change box, a few px off the
                                 object and holding the road beside it, otherwise drifts off it and measures the road's
                                 growth (``drive_4_h4``'s collider 7: warned 0.93 s before contact with it, not at all
                                 without; docs/history.md, "Shadow targets, session 18"). On (the default since session
                                 18); off = only boxes seeded on a uniform region.""", valid=Valid.boolean())
    merge_ttc: float = param(2.0, """Two targets that both measured a time to contact on the last frame, the larger at least
                             this many times the smaller, are never merged (:meth:`TargetLayer._merge`): two
                             objects whose contacts come apart, such as a collider's box grown over the view at its
                             contact and a second collider beside it (``texture_pan_4_h1``: with it 0 false episodes,
                             without 2), not one object's two boxes. 2 (the default since session 18: docs/history.md,
                             "Shadow targets, session 18"); 0 = off.""",
                             unit="ratio", valid=Valid.real(minimum=0))
    change_frames: int = param(4, """A faint candidate's box is the region that changed over this many
                               frames (:func:`change_box`): a slow edge moves a fraction of a pixel per
                               frame.""", unit="frames", valid=Valid.integer(1))
    min_growth: float = param(0.005, """A candidate becomes a target only when its box grew by at least this
                              much (log of the scale) over the last ``change_frames`` frames, alike in
                              both directions (``max_anisotropy``): a patch of background that slides
                              with a turning camera, a receding or a static object does not grow. 0.005
                              over 4 frames is a time to contact of 27 s at 30 fps. 0 = no test.""",
                              valid=Valid.real(minimum=0))
    max_targets: int = param(12, "Upper bound on simultaneous targets (no new candidate while this many exist).",
                             unit="targets", valid=Valid.integer(0))
    # --- the image measurement ------------------------------------------------------------
    patch: int = param(32, "Side of the resampled patch the alignment works on (:func:`align`).",
                       unit="samples", valid=Valid.integer(8, 256))
    margin: float = param(1.5, "Patch half-side = ``margin`` x half the box's larger side + 3 px.",
                          valid=Valid.real(minimum=1))
    iterations: int = param(10, "Most Gauss-Newton iterations per alignment.", valid=Valid.integer(1))
    max_residual: float = param(25.0, "Largest rms residual of an accepted alignment (0-255 scale).",
                                unit="grey levels", valid=Valid.real(minimum=0))
    remeasure: float = param(2.0, """Between frames more than one nominal frame apart (``nominal_fps``), a
                             growing track whose alignment fails takes the box measured afresh (the
                             change, else the edges) where its own motion carries it, when that box grew
                             by a log-scale within this factor of the one the motion predicts
                             (``TargetLayer._remeasure``; the 7.5 fps helmet clip). At the nominal rate
                             nothing changes. 1 = off.""", valid=Valid.real(minimum=1))
    max_fails: int = param(3, "Consecutive failed alignments after which a target is dropped.",
                           unit="frames", valid=Valid.integer(1))
    # --- time to contact and course -------------------------------------------------------
    nominal_fps: float = param(30.0, """The layer's frame counts (``window``, ``min_frames``, ``change_frames``,
                               ``confirm_frames``, ``evidence_frames``, ``hold_frames``, ``refind_frames``,
                               ``idle_frames``) are
                               spans of time at this rate: n frames = n / ``nominal_fps`` s, whatever the
                               camera's rate, a repeated frame no new observation and a dropped one time gone
                               (:meth:`TargetParams.span`). A fit needs at least 3 observations (``MIN_POINTS``) and
                               its window keeps at least ``window`` of them: a 7.5 fps camera gets its first
                               time to contact from 3 frames over 0.27 s and then fits up to 12 over 1.5 s,
                               a 30 fps one 5-12 over 0.13-0.37 s, a 60 fps one 9-23 (docs/model.md, "Time").""",
                               unit="frames/s", valid=Valid.real(minimum=1))
    window: int = param(12, """Frames of the ``1 / S`` line fit (:func:`fit_contact`) and of the course: the
                        observations of the last ``window - 1`` frame intervals (``nominal_fps``), at least
                        ``window`` of them.""",
                        unit="frames", valid=Valid.integer(3, 1000, also=">= min_frames"))
    min_frames: int = param(5, """Fewest frames a fit needs: observations over ``min_frames - 1`` frame
                            intervals (``nominal_fps``), at least 3.""", unit="frames",
                            valid=Valid.integer(3, 1000, also="<= window"))
    min_tstat: float = param(3.0, "The growth (the fit's slope) must be this many standard errors from 0.",
                             valid=Valid.real(minimum=0))
    max_ttc_s: float = param(10.0, "Longer times to contact are reported as None (no measurable approach).",
                             unit="s", valid=Valid.real(minimum=0))
    young_ttc: bool = param(True, """A target whose history is still too short for a fit (under ``min_frames``) shows
                            the time to contact of the fit over the observations it has and the growth its growth test
                            measured over the ``change_frames`` before its birth (at least 3 points), when that fit
                            passes the tests a time to contact must pass (``min_tstat``, ``max_ttc_s``, growth alike in
                            both directions): ``ttc_s`` and ``ttc_sigma_s`` only, set once every decision of the frame
                            is taken, so no warning, course, countdown or held time to contact rests on it
                            (``warning.young``). False = no time to contact before ``min_frames`` (main's before
                            session 46). On since session 46 (docs/history.md, "A young target's time to contact").""", valid=Valid.boolean())
    heading: tuple[float, float] | None = param(None, """Heading point (x, y): where the camera moves to (the
                                                focus of expansion), in the pixels of the input, as every
                                                output (``mlplc2.run`` and ``mlplc2 run --heading X,Y``: the
                                                video's, whatever ``resize`` and the models' working width; a
                                                model stepped by hand: the frames given to ``step``); the model
                                                maps it to its working pixels. None = measured from the images
                                                while the camera translates (gaze stabilisation), else the
                                                principal point ((W - 1) / 2, (H - 1) / 2): the camera moves
                                                along its optical axis, or stands still.""",
                                                unit="px", valid=Valid.point())
    course_yaw: bool = param(True, """From a camera whose heading is steady (``TargetLayer.steady``, as
                             ``alarm_path``), the horizontal course is fitted in the vehicle's axes: the box's
                             centres in each frame's own pixels (its yaw kept), against the heading, rather than
                             stabilised (less the camera's turn). A vehicle that turns turns its path with its
                             yaw, and its heading stays put in the image: a lead vehicle on the same curve stays
                             ahead in its axes while it drifts sideways once the yaw is taken out, and a far
                             object beside the curve sweeps across it (a lateral ``Z`` times the yaw rate),
                             which the stabilised course does not see. What will hit is judged in the vehicle's
                             axes at contact (the benchmark's truth for a camera on a path). The vertical course
                             stays stabilised (a pitch bounce, a roll or a shake of the camera does not turn the
                             vehicle's path); without a steady heading (a camera that pans, tilts or only
                             shakes, which has no path to turn) both stay stabilised. False = off (on since
                             session 43: through 90 degrees holdouts 27-29 a collider more, 86 -> 87 of 89, no
                             collider or lead lost over eleven sets, the real clips' warnings as before; both axes
                             kept gave a hand-held camera's shake and a drone's pitch for turns, and a real clip a
                             false warning: docs/history.md, "The course in the vehicle's axes, and a box a few
                             pixels across").""", valid=Valid.boolean())
    course_centre: bool = param(True, """The course (step 6) from the box's own expansion centre
                                (:func:`~mlplc2.targets.contact.fit_centre_course`: the slope of its centre against
                                its size, neither the heading point nor the time to contact needed) rather than the
                                line of the centre's offset from the heading in box widths evaluated at the fit's
                                time to contact, which misses by that offset times the time to contact's relative
                                error: a collider far off the principal point in stabilised pixels (the one a
                                panning camera turns towards, 4-8 widths off at 1-2 s) got courses of 2-28 widths
                                from a time to contact 20-40 % long, and warned late or never
                                (``texture_pan_1_h41_f90``: 28 -> 1.0 widths over its last 2 s, the truth 0.2; its
                                own expansion centre gives 0.2-0.3). On a frame where a field of the target is in
                                collision alarm, the shorter of the two (the alarm is evidence of its own, step 7:
                                only both courses veto it): the expansion centre's course has the box's error, a box
                                on a part of its object that does not scale with it (``crossing_car_strong_light``'s
                                van: 1.0-1.17 against the line's 0.88-0.94, beyond ``max_miss`` at its alarm).
                                False = the line alone (as until session 52); docs/history.md, "The course from the
                                box's own expansion centre".""", valid=Valid.boolean())
    centre_growth: float = param(0.05, """With ``course_centre``: the least growth (log-scale, largest less
                                 smallest) over the course's points for the expansion centre's course; under it
                                 the line alone (a box that hardly grew tells no slope of its centre against its
                                 size).""", valid=Valid.real(minimum=0))
    border: float = param(2.0, """A box whose edge lies within this of the image's border is cut: it gives
                          neither the object's size nor its centre, so the course is fitted only from the
                          last ``window`` frames of the track where the box lay wholly inside (however
                          old: the course of an object seen whole holds while its growing box is cut);
                          with fewer than ``min_frames`` such frames, no course and no warning.""", unit="px", valid=Valid.real(minimum=0))
    max_anisotropy: float = param(0.35, """Largest difference of the vertical and horizontal growth
                                  (log ky - log kx over the fit's frames) relative to the growth of a
                                  looming target: a fronto-parallel object grows alike in both directions
                                  (0), the ground ahead of a moving camera twice as fast vertically
                                  (0.67), a wall beside its path the other way round (-0.67).""",
                                  valid=Valid.real(minimum=0))
    # --- the warning ------------------------------------------------------------------------
    horizon_s: float = param(1.0, "A target warns only when its ``ttc_s`` is at most this ...", unit="s",
                             valid=Valid.real(minimum=0))
    max_miss: float = param(1.0, """... its predicted miss at contact at most this (the length of the
                            offset of its centre from the heading, horizontally in its widths, vertically
                            in its heights) ...""", unit="object extents",
                            valid=Valid.real(minimum=0))
    max_ttc_sigma: float = param(0.3, "... its contact time known to this fraction (standard error / ttc) ...",
                                 valid=Valid.real(minimum=0))
    evidence_frames: int = param(15, """... and it shows looming evidence: one of its attention fields
                                 answered within this many frames ...""", unit="frames", valid=Valid.integer(0))
    confirm_frames: int = param(6, "... or its growth has been significant for this many frames in a row.",
                                unit="frames", valid=Valid.integer(0))
    evidence_bridge: int = param(15, """... and a streak of at least ``confirm_frames`` fits that lapsed for at most this
                                 many frames (its time to contact held meanwhile) goes on where the fit resumes: the
                                 growth seen before the lapse still counts (a lead vehicle's box that stretched for ten
                                 frames; ``warn_through``'s span). 0 = off (on since session 35: holdouts 59-64 two
                                 colliders more, one false episode; thirty-nine sets one collider more, 23 leads longer,
                                 six false episodes more; docs/history.md, "A streak of fits that lapses").""", unit="frames", valid=Valid.integer(0))
    confirm_birth: bool = param(True, """... counted from the target's birth when the growth test made it a target
                                (``min_growth`` over ``change_frames``, not a field alarm) and its fit has given a
                                time to contact on every frame since the first it could (``min_frames``): the
                                growth seen before its birth and every fit since are one streak. False = from its
                                first time to contact (docs/history.md, "Objects missed", session 13).""",
                                valid=Valid.boolean())
    confirm_birth_drift: float = param(0.2, """... ``confirm_birth`` only for a box that holds the heading (the measured one,
                                       else the principal point) or whose centre drifted away from it by at most this
                                       fraction of the static world's drift (:func:`~mlplc2.targets.warning.drift`; as
                                       ``cut_drift``): the ground at the view's foot grows from its birth too, drifting
                                       as the static world does.""", valid=Valid.real(minimum=0))
    slow_evidence: bool = param(True, """... or (on a frame more than one nominal frame after the frame processed
                                before it: a camera slower than ``nominal_fps``, or a dropped frame; not a gap in
                                the track's own observations) its log-scale rose at every observation
                                over the last ``confirm_frames - 1`` frames, from one at or before their start: a
                                7.5 fps camera's streak of estimates would need 3 of its frames (0.53 s after the
                                first of the fit), longer in time than at 30 fps (the 7.5 fps helmet clip's first
                                time to contact comes 4 frames = 0.13 s before contact). False = off (docs/history.md,
                                "A slow camera's first estimate").""", valid=Valid.boolean())
    alarm_warns: bool = param(True, """... or (True, the default since session 8: the real clips' warnings
                              3/9 -> 6/9, the suite's 41/45 -> 43/45, at 2.57 -> 3.09 false episodes per
                              1000 frames; docs/model.md) one of its attention fields is in collision alarm (the paper's
                              fatal field, ``Params.alarm_threshold``), its box grew, and its own fit says
                              nothing against it (no time to contact from a history of ``min_frames``, one
                              beyond the horizon, a course beyond ``max_miss``; without a course, a box
                              cut by the border, or one neither on the path now nor keeping its bearing
                              while it grows: :func:`~mlplc2.targets.warning.on_path`,
                              :func:`~mlplc2.targets.warning.keeps_bearing`); such a field belongs only
                              to a target whose box holds its centre, else it seeds one that needs only
                              some growth, with the field's extent when no box is found.""",
                              valid=Valid.boolean())
    cut_onset_s: float = param(0.5, """A warning begins on a box cut by the image's border (``border``) only
                               while ``ttc_s`` is at least this (and with a time to contact); once a target
                               has warned, it warns on while cut. The static world beside the path and the
                               ground sweep out of view through the border with a short time to contact
                               (the drive scenes' false episodes that begin cut: 0.12-0.47 s), while an
                               object on a collision course is seen coming. 0 = off.""", unit="s",
                               valid=Valid.real(minimum=0))
    cut_drift: float = param(0.2, """... unless the cut box keeps its bearing while it grows: its centre drifted
                             away from the heading by at most this fraction of the static world's drift over
                             the same growth (:func:`~mlplc2.targets.warning.drift`, against the measured
                             heading, else ``heading`` or the principal point; measured only where the
                             static world's drift is at least 2 px). The static world beside the path expands
                             about the heading (1) as it sweeps out of view; an object on a collision course
                             near the border keeps its bearing (0) and often shows itself whole only for a
                             few frames. 0 = off (every cut box under ``cut_onset_s`` is held back;
                             docs/history.md, "Objects missed", session 11).""", valid=Valid.real(minimum=0))
    cut_course: bool = param(True, """A target whose box is cut by the border (``border``) has no course (the
                             course takes only the boxes wholly inside); with ``cut_course`` such a box that
                             keeps its bearing while it grows (``cut_course_drift``) stands on a collision course
                             and may warn from its fit's time to contact (:func:`~mlplc2.targets.warning.cut_course`;
                             on since session 12: it warned ``drone_0_h1`` and ``drone_4_h3``, no false warning
                             added on any suite or real clip). False = off (docs/history.md, "Objects missed",
                             session 12).""",
                             valid=Valid.boolean())
    cut_course_drift: float = param(0.0, """... ``cut_course``'s largest drift of the cut box's centre away from the
                                   heading, as a fraction of the static world's (:func:`~mlplc2.targets.warning.drift`;
                                   0: it keeps its bearing or comes nearer the heading). Lower than ``cut_drift``:
                                   the border holds a cut box's centre in view, so the static world's drift is
                                   measured short there (the ground at a drone's frame foot: 0.15-0.19).""",
                                   valid=Valid.real())
    onset_miss: float = param(0.8, """A warning that the fit's course begins (no field of the target in collision
                              alarm this frame) begins only on a predicted miss of at most this; once the target
                              has warned, ``max_miss`` (and the field alarm with a course keeps ``max_miss``:
                              issue 22, item 4). A passing object's box holds its sweep and the background
                              beside it, so its miss is measured far too short (0.6-1.0 for a true 2.2-4.5
                              widths), and it crosses ``max_miss`` from above; the colliders' fit onsets lie
                              at 0.03-0.78. 0 = off (0.8, the default since session 11: false episodes per
                              1000 frames 1.24 -> 1.13 standard, 1.75 -> 1.34 holdout 1, no collision or lead
                              lost; docs/history.md, "A course that crosses max_miss").""",
                              valid=Valid.real(minimum=0))
    slow_onset: bool = param(True, """``onset_miss`` does not hold a track's first time to contact (no estimate before
                             it) on a frame more than one nominal frame after the frame processed before it
                             (a camera slower than ``nominal_fps``, or a dropped frame; the track observed on
                             it): that course has crossed nothing from above (a passing object's falls
                             through ``max_miss`` over its estimates), and a slow camera's first fit comes
                             late (the 7.5 fps helmet's at 4 frames = 0.13 s before contact, course 0.85).
                             ``max_miss`` holds it. False = off (docs/history.md, "A slow camera's first estimate").""", valid=Valid.boolean())
    countdown_frames: int = param(3, """A target's warning goes on only while its time to contact counts down: once it
                                  has warned, a warning frame whose ``ttc_s`` exceeds the one the target had this
                                  many frames (at ``nominal_fps``) before by more than its standard error
                                  (``ttc_sigma_s``) ends its warning for good (``Track.spent``).
                                  A box that slid off its object onto the road or the background, or a passing
                                  object's, stops growing at the fitted rate, and its time to contact rises; an
                                  approach's falls by a frame's time each frame. 0 = off (3, the default since
                                  session 11: with ``onset_miss``, false episodes per 1000 frames 1.13 -> 0.93
                                  standard, 1.34 -> 1.13 holdout 1, no collision or lead lost; docs/history.md,
                                  "A course that crosses max_miss").""", unit="frames", valid=Valid.integer(0))
    rise_sigma: bool = param(True, """With ``countdown_frames``: a time to contact rises when it exceeds the older one by
                             more than the standard error of their difference (both estimates' standard errors
                             combined), not by this frame's alone. False = this frame's alone (as until session 19;
                             on since session 20, with ``warn_through`` and ``rise_streak``: docs/history.md, "A warning
                             held to contact").""", valid=Valid.boolean())
    rise_streak: bool = param(True, """With ``countdown_frames``: a running warning's time to contact rises only against an
                              estimate of the same run of fits (``Track.streak_since``): the first fits after a gap
                              (a box re-seated, grown over the view) start from another box and are not compared with
                              the time to contact held through the gap. False = compared with any (as until session
                              19; on since session 20: docs/history.md, "A warning held to contact").""",
                              valid=Valid.boolean())
    held_onset: int = param(15, """A warning may begin on a frame whose fit gives no time to contact, on the one held
                            (``hold_frames``: the last one counted down, shown as ``ttc_s`` with its ``ttc_age_s``),
                            when the fit lapsed after a streak of at least this many fits in a row: once the held time
                            to contact is within ``horizon_s``, on a course held within ``onset_miss``, on a box not cut
                            by the border (``held_cut``: or one that keeps its bearing), not off the path
                            (``path_drift``) and not flat (``flat_onset``). A collider's box that slides off it as it
                            nears (a drone's over a textured ground) loses its fit just before its time to contact
                            enters the horizon, and warned never. 0 = off (as until session
                            26). 15 since session 26: over fifteen sets two colliders gained (``drone_4_h26``'s), one
                            false episode added (``ground_static_4_h30``); 5 added seven (docs/history.md, "The box on
                            what moves with it, on a cut box and from a moving camera").""", unit="fits",
                            valid=Valid.integer(0))
    onset_px: float = param(4.0, """A warning begins only on a box at least this large on its smaller side (every
                            route: the fit's, the field alarm's, ``held_onset``; a warning that began goes on). The
                            image alignment measures a box's growth from the grey levels inside it: across a few
                            pixels a tenth of a pixel of its edges' noise is a few percent of its size a frame, the
                            growth of an approach a second away (a pan's or a tilt's speck of texture, a 2.5 x 7 px box
                            on a tilt). 0 = off (4 since session 43: the five onsets under 4 px over nine sets
                            were all off every object, none between 4 and 6 px; false episodes on holdouts 30-32,
                            86-88, 89-91 and the held-back 92-94 one fewer each, no collider or lead changed;
                            docs/history.md, "The course in the vehicle's axes, and a box a few pixels
                            across").""", unit="px", valid=Valid.real(minimum=0))
    onset_confirm: bool = param(True, """A warning is shown from the second frame in a row on which the warning rule
                                decides it (every rule above and the layer's own, ``contact_blind``, ``heading_growth``,
                                ``onset_support``): a warning decided on one frame alone, a rule's threshold crossed by
                                one frame's noise, is never shown, and an onset waits one frame; not where a field of
                                the target is in collision alarm that frame (the paper's alarm is evidence at once,
                                issue 22 item 4: the warning comes no later than the field alarm), nor on a frame that
                                follows the one before by more than one nominal frame interval (a camera slower than
                                ``nominal_fps``, whose frames lie further apart than the wait; the 7.5 fps helmet clip's
                                only warning is its last frame before contact). The rule's own state
                                (``Track.decided``, ``warned``, ``last_warned``) follows the decision, so nothing but
                                what is shown changes. False = shown at once (main's before session 45). On since
                                session 45: five sets of six moving settings (445 colliders) and their replicate,
                                false episodes 53 -> 47 and 52 -> 45 (0.55 -> 0.48 and 0.53 -> 0.46 per 1000 frames),
                                false frames 308 -> 277 and 229 -> 200, colliders 428 -> 426 and 428 -> 424 (the ones
                                lost warned on one frame only, 3-8 % of their approach, or on the last frame before
                                contact), lead median and 10th percentile 0.03 s shorter; the real clips' warnings
                                as before; docs/history.md, "Where a first warning moves, traced to its rule").""",
                                valid=Valid.boolean())
    held_cut: bool = param(True, """``held_onset`` also on a box cut by the border that keeps its bearing against the
                           measured heading (:func:`~mlplc2.targets.warning.cut_keeps_bearing`: drifted from the
                           heading by at most ``cut_drift`` of the static world's drift, the test a fit's warning on a
                           cut box passes under ``cut_onset_s``): a lead vehicle's box that reaches the border as it
                           nears grows wider than tall and loses its fit with its time to contact held just beyond the
                           horizon (``drive_4_h43``: 52 fits, 1.04-1.06 s, the truth 1.11-0.97 s, a course missing by
                           0.13-0.18), and warned never. The static world that sweeps out through the border drifts
                           with it. Off: never on a cut box (as until session 34). On since session 34: over
                           thirty-six sets that collider gained (0.84 s ahead), nothing else moved; docs/history.md,
                           "A cut box's time to contact held".""", valid=Valid.boolean())
    warn_through: int = param(15, """A running warning goes on through frames whose fit gives no time to contact (its
                              growth not significant or not isotropic for a while: a box re-seated, two colliders
                              overlapping), on the time to contact held (``hold_frames``: the last one counted down)
                              and its course, within ``horizon_s`` and ``reonset_miss`` (``max_miss`` while a field of it alarms:
                              ``through_alarm``), for up to this many frames after
                              the last fit. 0 = off (as until session 19): a warning needs this frame's fit, and a
                              collider's warning lapsed for 0.7-1.2 s before its contact. 15 since session 20 (with
                              ``rise_sigma`` and ``rise_streak``): warned colliders silent for 0.2 s or more before
                              their contact 9 -> 5 on the standard suite (and 4 -> 3 of its 8 warned real
                              collisions), 6 -> 3, 6 -> 3, 8 -> 6, 9 -> 4 on holdouts 15-18 (17 and 18 held back), none
                              warned later or not at all
                              (docs/history.md, "A warning held to contact").""", unit="frames",
                              valid=Valid.integer(0))
    through_alarm: bool = param(True, """With ``warn_through``: a running warning goes on, where its own fit does not, on a
                                course within ``max_miss`` (not ``reonset_miss``) while a field of it is in collision alarm
                                this frame: the field alarm is evidence of its own (issue 22, item 4), and the box of a part
                                of a large object that fills the view (its course counted in the part's extent) misses by
                                more than ``reonset_miss`` while the object hits. False = ``reonset_miss`` always (as until
                                session 24).""", valid=Valid.boolean())
    alarm_hold: bool = param(True, """A running warning goes on on every frame a field of its target is in collision
                             alarm (the paper's fatal field) while the target has a time to contact (its fit's this
                             frame or the one held, ``hold_frames``), whatever its course, through the border too
                             (not ``cut_exit``), until it is spent (``countdown_frames``)
                             (``warning.alarm_holds``): the box of a part of an object that fills the view misses, in
                             the part's own extent, by more than the object, and its fit lapses as the box stretches,
                             while the paper's alarm goes on to the contact. False = the alarm carries a running
                             warning only through a frame without a fit, on a course within ``max_miss``
                             (``through_alarm``; main's before session 46). On since session 46 (docs/history.md,
                             "A warning held by the field alarm").""", valid=Valid.boolean())
    countdown_onset: bool = param(True, """With ``countdown_frames``: a warning begins only while the target's time to contact
                                  counts down: a frame whose ``ttc_s`` exceeds the one the target had ``countdown_frames``
                                  frames before (:func:`~mlplc2.targets.warning.rises`; by more than their standard
                                  error with ``countdown_sigma``, else by any amount) does not begin a warning; it is
                                  held back, not ended.
                                  The ground beside the path as it nears the frame's foot holds a time to contact near
                                  ``horizon_s`` that does not fall, while an approach's falls by a frame's time each frame.
                                  False = off (on since session 13: holdout 3's false episodes per 1000 frames 0.72 ->
                                  0.62 with ``flat_onset``, no collision, lead or real clip changed; docs/history.md,
                                  "A flat box across the path").""",
                                  valid=Valid.boolean())
    countdown_sigma: bool = param(True, """With ``countdown_onset``: the time to contact rises only where it exceeds the
                                  older one by more than the standard error of their difference (both estimates'
                                  ``ttc_sigma_s`` combined, as ``rise_sigma``) and within one run of fits (as
                                  ``rise_streak``): a fit that underestimated an approach's time to contact early (a
                                  box that grew over its background at first) rises within its own noise as it
                                  settles, and each such frame counted towards ``stall_hold`` until the target could
                                  never warn (``texture_pan_1_h74``'s collider, its fit within 0.05 s of the truth
                                  over its last second, never warned). False = by any amount (until session
                                  39; docs/history.md, "A rise within the fit's noise").""", valid=Valid.boolean())
    onset_fall: float = param(0.3, """A warning begins only on a time to contact that falls at least this fast (s per s): a
                              frame whose ``ttc_s`` lies above the one the target had ``fall_frames`` frames (at
                              ``nominal_fps``) before, in the same run of fits, less this rate times the time between
                              them, does not begin a warning; it is held back, not ended. An approach at a constant
                              speed falls at 1 (tau-dot = -1); one that brakes to stop short of the camera at 0.5 or
                              less (Lee 1976); the ground beside the path, followed by a box that slides along it as
                              the camera nears, holds a time to contact that hardly falls. 0 = off (as until session
                              27). 0.3 since session 27, with ``stall_hold`` and ``stall_sigma``: over eighteen sets
                              four false episodes fewer, no collider lost, one warned a frame later (docs/history.md,
                              "A time to contact that does not fall").""", unit="s/s",
                              valid=Valid.real(minimum=0, maximum=1))
    stall_hold: int = param(5, """A target whose warning was held back on this many frames as its time to contact did not
                            fall (``onset_fall``, ``countdown_onset``) never begins one: a time to contact that stayed
                            within the horizon without falling is no approach, even where it falls later (the ground's
                            box as it nears the frame's border). 0 = off (as until session 27; ``onset_fall`` alone
                            delays those warnings but removes none).""", unit="frames", valid=Valid.integer(0))
    stall_sigma: bool = param(True, """With ``onset_fall``: a time to contact stalls only where it lies above the older one less
                              ``onset_fall`` times the time between them by more than the standard error of their
                              difference (both estimates' ``ttc_sigma_s`` combined): a fit across a box re-seated is
                              too uncertain to say. False = by any amount (over eighteen sets a collider 0.33 s later,
                              two others a frame or two; docs/history.md, "A time to contact that does not fall").""",
                              valid=Valid.boolean())
    fall_frames: int = param(6, """The frames (at ``nominal_fps``) over which ``onset_fall`` compares a target's time to
                             contact with its own older one (its newest estimate at least that old, of its own fits or
                             held from them); none: no test.""", unit="frames", valid=Valid.integer(1))
    cut_exit: float = param(0.5, """Once a target has warned, a frame on which its box is cut by the image's border
                            (``border``) while it does not hold the heading (the measured heading, else ``heading`` or
                            the principal point: :func:`~mlplc2.targets.warning.holds`) and its course misses by more
                            than this (``miss``; 0.5: the heading lies outside its box at contact) is not a warning,
                            unless its warning began on a cut box (``cut_onset_s``, ``cut_drift``, the field alarm):
                            a passing object, the ground or a roadside object leaves the view through the border beside
                            the camera's path, while the box of an object on a collision course spreads over the path.
                            The warning is held back, not ended (:func:`~mlplc2.targets.warning.exits`). 0 = off (0.5,
                            the default since session 12: false episodes per 1000 frames 0.82 -> 0.72 standard (0.35 ->
                            0.25 % of frames), 1.34 -> 1.24 holdout 2, holdout 1's frames 0.55 -> 0.51 %, no lead or real
                            clip changed; ``texture_tilt_1``'s collider, warned only by a passing object's box over it,
                            lost; docs/history.md, "A warning that leaves through the border").""",
                            unit="object extents", valid=Valid.real(minimum=0))
    bearing_drift: float = param(0.3, """The field alarm without a course (a young track, or a seed on its first frame)
                                 warns on a box off the path only if it keeps its bearing while it grows
                                 (:func:`~mlplc2.targets.warning.keeps_bearing`): its centre drifted away from the
                                 heading by at most this fraction of the static world's drift over the same growth
                                 (0: an object on a collision course, 1: the static world). The real clips' first
                                 warnings by it drifted 0.03-0.25, the drive's colliders' -0.02-0.06, its false onsets
                                 0.06-0.38. 0.3 since session 50 (0.4 since session 15, before that 0.5, halfway, the
                                 constant ``DRIFT_FRACTION``): over nine sets of the six moving settings 784 of 800
                                 colliders warned as before, every lead the same, false episodes 77 -> 74 (three of the
                                 drive's, 1-4 frames each); docs/history.md, "The bearing kept, 0.3, session 50". 0.4
                                 (session 15): holdout 4's false episodes per 1000 frames 0.51 -> 0.41 (the ground's
                                 seed at 0.45 where no heading is measured); "False warnings, session 15"; session 10:
                                 "A warning that begins off the path", (H)).""", valid=Valid.real(minimum=0))
    alarm_path: float = param(0.5, """From a camera whose heading is steady (measured on at least 80 % of the last 15
                              processed frames, 10 seen at least: ``TargetLayer.steady``), a field in collision alarm
                              no longer exempts a warning that its course would begin from the drift test of
                              ``path_drift``: on a box that does not hold the heading and drifts away from it by more
                              than this fraction of the static world's drift, the alarm with a course begins no
                              warning (the static world, or an object passing beside the path, its box too wide for
                              its course). Halfway between an object on a collision course (0) and the static world
                              (1), more lenient than ``path_drift`` (0.4), the alarm being evidence of its own: at 0.4
                              a collider's young box settling onto it (drift 0.43) lost 0.87 s of lead. Without a
                              course, or where the heading is measured on fewer frames (the real dashcam clips: 3-45 %
                              of their frames; two of their colliders' first warnings drifted 0.80 and 1.34 against a
                              heading measured so seldom), the alarm exempts it as before. 0 = off (0.5 since session
                              42: false episodes per 1000 frames through 90 degrees 0.51 -> 0.31 (standard), 0.57 ->
                              0.41 (held-back holdouts 33-35), through 60 degrees 0.67 -> 0.46 (held-back holdouts
                              89-91, one lead 1.00 -> 0.70 s), no collider lost, the real clips unchanged;
                              docs/history.md, "The alarm's course against a steady heading").""",
                              valid=Valid.real(minimum=0))
    bearing_isotropic: bool = param(True, """A warning that the field alarm without a course begins on a box off the
                                    path because it keeps its bearing over its own history (two observations or
                                    more, ``bearing_drift``) begins only where that box grew alike in both
                                    directions: its log-anisotropy gained at most ``max_anisotropy`` times its
                                    log-growth plus the noise of one frame's alignment
                                    (:func:`~mlplc2.targets.warning.grew_alike`, ``SKEW_NOISE`` 0.05). A box over
                                    the ground, along a wall or across the gap beside a passing object stretches
                                    along one axis while the edges it lies between hold its centre. False = off (on
                                    since session 42: false episodes, the standard suite 5 -> 3, holdouts 83-85
                                    8 -> 7, through 90 degrees holdouts 30-32 18 -> 16 and 27-29 13 -> 12, the
                                    held-back holdouts 86-88 and 33-35 byte for byte, no collider, lead or real
                                    clip changed; docs/history.md, "A bearing kept by a box that
                                    stretches").""", valid=Valid.boolean())
    alarm_onset_miss: bool = param(True, """The field alarm with a course begins a warning beyond ``onset_miss`` (up to
                                   ``max_miss``) only on its first frame in a row (``Track.alarm_run``): an alarm that
                                   lasted while the course said the object passes, and warns once its course falls
                                   under ``max_miss``, is a passing object's course measured short (as the fit's, which
                                   ``onset_miss`` holds); the real colliders' alarms with a course began on their first
                                   frame (``night_rear_end`` 0.88, ``crossing_car_strong_light`` 0.73). A target that
                                   warned goes on as before. False = off (on since session 15: holdout 1's false
                                   episodes per 1000 frames 0.82 -> 0.72 with ``bearing_drift``, ``drive_1_h1``'s
                                   parked car (course 1.21 -> 1.00 on its alarm's 7th frame), no collision, lead or
                                   real clip changed; docs/history.md, "False warnings, session 15").""", valid=Valid.boolean())
    alarm_onset_course: bool = param(True, """With ``alarm_onset_miss``: the frames of the alarm that count are those on which the
                                     target's fit gave a course (``Track.alarm_courses``): an alarm that lasted while
                                     the target had no course yet (a young track, its no-course alarm held back by
                                     ``path_drift`` or ``bearing_drift``) has not been judged on a course, so its first
                                     course begins a warning up to ``max_miss``, as an alarm on its first frame does.
                                     Whether the course comes on the alarm's first frame or a frame later is a knife edge
                                     (issue 22, item 7: ``night_rear_end.mp4``'s van, course 0.88 on the alarm's first
                                     frame on the clip, 0.82 on its 5th on the 320x240 copy). False = off (on since
                                     session 17: that copy warns at 102 on the van as the clip does (none before); the
                                     standard suite, its real clips and holdouts 1-4, 6 and 8 unchanged; docs/history.md,
                                     "The same warning whatever the encoding, session 17").""",
                                     valid=Valid.boolean())
    cut_exit_onset: bool = param(True, """With ``cut_exit``: no warning begins either on a frame on which ``cut_exit``
                                 would hold one back (the box cut by the border, not holding the heading, its course
                                 missing by more than ``cut_exit``), whatever began it (the fit, the field alarm with a
                                 course): the ground leaving the view through the border beside the path, its time to
                                 contact still ``cut_onset_s`` away (0.87-0.97 s, courses 0.66-0.92). The colliders
                                 whose warnings began on cut boxes did on courses of 0.09-0.39. False = off (on since
                                 session 15: false episodes per 1000 frames holdout 1 0.93 -> 0.82, holdout 3 0.51 ->
                                 0.41 (0.28 -> 0.10 % of frames), holdout 4 0.62 -> 0.51 with ``contact_blind``, no
                                 collision, lead or real clip changed; docs/history.md, "False warnings, session 15").""",
                                 valid=Valid.boolean())
    exit_ahead: bool = param(True, """With ``cut_exit_onset``: no warning begins either on a box wholly inside the frame
                             that the same test refuses one frame ahead: its box moved and grown as over its last
                             frame (:meth:`~mlplc2.targets.track.Track.cut_ahead`) is cut by the border, does not hold
                             the heading, and its course misses by more than ``cut_exit``. Such a warning lasted one
                             frame: ``cut_exit`` held it back on the next. False = off (on since session 20: false
                             episodes per 1000 frames holdout 15 0.93 -> 0.82, 16 0.41 -> 0.31, held-back 19 0.82 ->
                             0.72, the standard suite and holdouts 17, 18, 20 unchanged, no collision, lead, real clip
                             or first warning of a re-encoded copy changed; docs/history.md, "A warning one frame
                             before the border").""", valid=Valid.boolean())
    alarm_reseat: bool = param(True, """With ``alarm_warns``: when the box found for the seed of an attention field in
                               collision alarm is a uniform region's (``uniform_tol``) and holds a smaller target
                               (most of that target lies in it, so the seed is taken as a part of it), the target is
                               put on the seed's box, its history carried with it
                               (:meth:`~mlplc2.targets.track.Track.reseat`), and follows the region from then on
                               (``uniform_reseat``): the field alarm's box is the object, the smaller target an edge
                               or a strip of it, whose course beside the object's centre vetoed the alarm. False =
                               off (session 21: holdout 22's missed lead vehicle warned 2.21 s ahead, no false
                               frame added on six sets; docs/history.md, "An alarm seed over a smaller
                               track").""", valid=Valid.boolean())
    uniform_adopt: bool = param(True, """A target that is not a uniform region's (``uniform_tol``), and has not warned, whose
                                centre lies on a uniform region that is a compact object (``uniform_fill``,
                                ``uniform_aspect``; not touching the frame's border) larger than its box and holding
                                most of it, is put on that region, its history carried with it
                                (:meth:`~mlplc2.targets.track.Track.reseat`), and follows the region from then on
                                (``uniform_reseat``): its box was an edge or a strip of a uniform object, seeded
                                where only that edge changed (an object that came into view through the border,
                                whose region was cut then), and grew one way only. False = off (on since session
                                36: thirty-nine sets three colliders more, the same false episodes; docs/history.md,
                                "A strip of a uniform object, and a cut box's bearing").""", valid=Valid.boolean())
    alarm_split: float = param(3.0, """With ``alarm_warns``: a field in collision alarm whose owner (the smallest
                               track whose box holds it) has not warned (``split_warned``: lately) and has no
                               time to contact within ``horizon_s`` (none, or its last one beyond; ``split_course``: or
                               one on a course that misses) is a seed of its own (issue 22 item 4: a
                               seed with its own box). When the box found for it grows (the growth test with the
                               alarm), lies on the camera's path (it holds the measured heading,
                               :func:`~mlplc2.targets.warning.holds`, or keeps its bearing, ``split_bearing``; any box
                               where no heading is measured) and its
                               owner is at least this many times its size, the owner is dropped and the seed's box
                               is a new target that owns the field. A box over
                               the alarm's object and its surround (a lead vehicle with its neighbours, a strip
                               across the road) has a time to contact and a course that are neither's and vetoes
                               the alarm; off the path, where the seed's box drifts as the static world does, the owner's
                               veto stands (a passing object's alarm). 0 = off
                               (3, the default since session 30: over twenty-four sets 1041 -> 1044 of 1072
                               colliders warned, none lost, false episodes 111 -> 114; docs/history.md, "An alarm
                               seed with its own box").""",
                               unit="x the seed's box", valid=Valid.real(minimum=0))
    view_hold: bool = param(True, """A target whose warning runs and whose box is exactly as wide or as tall as the
                            frame (within 1 px: the object fills the view and its box, a uniform region's, is cut at
                            the frame's edges, so its growth is no longer the object's) takes no new time to contact
                            from its fit: its last one is held and counted down (``hold_frames`` and
                            ``warn_through`` waived), its warning goes on while that lasts (within ``horizon_s`` and
                            ``reonset_miss``), and it is not lost when its alignment fails (the view is uniform).
                            Once the contact that time to contact predicts has passed, a target that has warned and
                            whose box is the view is dropped, not to be refound (``refind_frames``): the object has
                            reached the camera. False = off (session 21: warnings lapsed 43 -> 39 on six sets, no
                            collider, lead or false episode changed; docs/history.md, "A warning over an object
                            that fills the view").""", valid=Valid.boolean())
    heading_growth: float = param(0.7, """From a translating camera (a measured heading, ``CameraMotion.heading``), a
                                  warning does not begin on a box that holds the heading (:func:`~mlplc2.targets.warning.holds`)
                                  where the patch about the heading (``heading_patch``) grew, over ``change_frames``,
                                  by less than this fraction of what the box's time to contact predicts, within twice
                                  its standard error (:func:`~mlplc2.targets.warning.heading_grows`): the point of the
                                  static world that the camera will hit is the one at the heading, so what will hit
                                  grows there. A box over the ground and the far scene above it, or over a passing
                                  object and the ground beside it, expands about the heading with the near ground's
                                  short time to contact (its course is short), while at the heading lies the far
                                  scene, which does not grow. A uniform patch (a box that is a uniform region's, or a
                                  patch whose grey levels vary by less than ``uniform_tol``: the inside of a dark lead
                                  vehicle), a box under ``heading_min`` and a failed alignment are no test; a target that
                                  has warned goes on. 0 = off (0.7, the default since session 22: false episodes per 1000
                                  frames 0.41 -> 0.31 on holdout 22, 0.93 -> 0.72 on holdout 25, 1.03 -> 0.41 on holdout
                                  27, no collider or lead changed on ten sets; docs/history.md, "What lies at the
                                  heading").""",
                                  valid=Valid.real(minimum=0))
    split_bearing: bool = param(True, """``alarm_split``'s seed whose box does not hold the measured heading gets its
                                own box all the same where it keeps its bearing: over ``change_frames`` (its own
                                alignment) its centre drifted away from the heading by at most ``bearing_drift`` of
                                the static world's drift, as an object on a collision course beside the path does
                                (False: only a box that holds the heading). On since session 33: on the 600 scenes
                                with a measured heading of thirty sets one collider more (warned 1.72 s ahead), one
                                false episode fewer, no real clip changed; docs/history.md, "An alarm seed that keeps
                                its bearing".""", valid=Valid.boolean())
    split_course: bool = param(True, """``alarm_split`` also where the owner's last time to contact is within
                               ``horizon_s`` but its course misses (its last miss beyond ``max_miss``): a target that
                               will not warn vetoes the alarm inside it with a course that may be neither object's.
                               On since session 34 with ``split_warned``; docs/history.md, "An alarm seed under a target
                               that will not warn".""", valid=Valid.boolean())
    split_warned: bool = param(True, """``alarm_split`` also under an owner that warned before but not for more than
                               ``warn_through`` frames (``Track.last_warning``; without it, any owner that ever warned
                               keeps every alarm inside it): a box left over the view after its object's contact
                               (``drone_4_h29``: 206 x 236 px around a 12-20 px collider, 31 frames after its last
                               warning) no longer hides the next collider, while one that has just warned keeps the
                               alarm, which may still be its own object's. On since session 34 with ``split_course``:
                               thirty-three sets, two colliders more, as many false episodes; docs/history.md, "An
                               alarm seed under a target that will not warn".""", valid=Valid.boolean())
    split_passed: bool = param(True, """``alarm_split`` also under an owner whose contact has passed (its last time
                               to contact has run out with none since, ``passed_seeds``: the box of an object that
                               hit, left over the view), whatever its warning and time to contact (``split_warned``
                               and the horizon do not hold it), where a box of its own is found for the seed (not
                               the field's extent: the remains of the object that hit are no object). A second
                               object behind the first, on nearly the same line of sight, raises its field alarm
                               inside that box as it grows after the first one's contact, and was hidden by it
                               (``drone_4_h109``: two discs 13 frames apart, the second's alarm one frame after the
                               first one's contact). The seed still needs a growing box on the path and an owner at
                               least ``alarm_split`` times its size. On since session 51; docs/history.md, "A collider
                               behind a collider that hit".""",
                               valid=Valid.boolean())
    heading_patch: float = param(0.25, """The side of the patch about the heading (``heading_growth``) as a fraction of
                                 the box's smaller side: small enough to hold what lies at the heading, not the box's
                                 near ground.""", valid=Valid.real(minimum=0, maximum=1))
    heading_min: float = param(24.0, """The smallest box (its smaller side) whose heading patch is measured
                               (``heading_growth``): a smaller patch holds too few pixels to measure its growth.""",
                               unit="px", valid=Valid.real(minimum=0))
    onset_isotropy: float = param(0.5, """A warning does not begin on a box whose log-anisotropy accumulated since its
                                  birth (``Track.aniso``, from every alignment; since ``alarm_reseat`` put it on its object, if it did:
                                  ``Track.grown_from``) is more than this fraction of its log-scale accumulated since
                                  then (``Track.log_s``): an approaching object grows alike
                                  in both directions over its whole life, while a box that slid along an edge, over a
                                  passing object and its neighbour, or over the ground stretched in one; the growth
                                  test of the fit (``max_anisotropy``) sees only its window. A target that has warned
                                  goes on. Held only where the stretch is also at least ``onset_stretch``. 0 = off (0.5, the
                                  default since session 22: with ``heading_growth``, holdout 23's false frames 0.58 ->
                                  0.41 %, nothing else changed on ten sets; docs/history.md, "What lies at the
                                  heading").""",
                                  valid=Valid.real(minimum=0))
    onset_stretch: float = param(0.5, """The least log-anisotropy accumulated since its birth that ``onset_isotropy``
                                 holds against a box (its aspect changed by a factor of at least ``exp(0.5)`` = 1.65):
                                 a young box's anisotropy is mostly its alignment's noise, as large as its growth, and a
                                 real car turning across the path stretches too (the real clips' re-encoded and scaled
                                 copies' first warnings: 0.11-0.15 at log-scales of 0.08-0.14, 0.39 at 0.38; without
                                 this, three copies of ``crossing_car_strong_light`` never warned).""",
                                 valid=Valid.real(minimum=0))
    isotropy_uniform: bool = param(False, """In short: whether the "box stretched one way since its birth, so no
                                   warning begins" test (``onset_isotropy``) also applies to the box of a plain-coloured
                                   region. In full: ``onset_isotropy`` holds against a uniform region's box too
                                   (``Track.uniform``). Off (the default since session 23): a uniform region's box
                                   takes its aspect from its region measured afresh (``uniform_reseat``), not from
                                   the alignment, and a lead vehicle's region re-measured as it nears changes its
                                   aspect with no stretch of the object (holdout 30's ``drive_0_h30``: log-anisotropy
                                   1.09, its warning 2 frames later with it on; docs/history.md, "A uniform region's
                                   aspect").""", valid=Valid.boolean())
    onset_support: float = param(1.2, """In short: no warning begins where the object would miss by more than this many
                                 of its own widths, its width taken from the part of the box that moves with it,
                                 not the whole box. In full: a warning does not begin on a target whose course, counted in the extent of
                                 the part of its box that moved as the box did since the frame ``change_frames``
                                 before (its texture and edges, not a still background beside it:
                                 :func:`~mlplc2.targets.change.moving_extent`) rather than in the box's own extent,
                                 misses by more than this (object extents, as ``max_miss``): a box twice its passing
                                 object's size halves that object's course. 0 = off (1.2, the default since session
                                 23: false episodes lower on five of twelve sets, no collider lost; docs/history.md,
                                 "The course in its object's own extent").""",
                                 valid=Valid.real(minimum=0))
    support_min: int = param(100, """The fewest pixels of a box that must move with it for ``onset_support`` to
                             test it (fewer: no test; a small or plain object's few pixels give no extent).""",
                             valid=Valid.integer(1))
    support_reseat: float = param(1.5, """A box more than this many times as wide (or as tall) as the part of it that moves
                                  with it (``onset_support``'s measurement, :func:`~mlplc2.targets.change.moving_extent`,
                                  at least twice ``support_min`` pixels) is put on that part, on that axis (its span times
                                  1.1, the 5th-95th percentile's), its history carried (:meth:`Track.reseat`), where at least
                                  ``support_still`` of the box beyond that part is seen to stay still: a box grown over the
                                  background beside its object measures neither the object's growth nor its course.
                                  Only on a target that has had a time to contact of its own, not on a uniform region's box
                                  nor on one cut by the border, and never onto a part of another target; on any frame.
                                  0 = off (as until session 25).""",
                                  valid=Valid.real(minimum=0))
    support_still: float = param(0.5, """``support_reseat`` cuts a box down on an axis only where at least this share of
                                 the box's pixels beyond the part that moves with it are seen to stay still (the still
                                 scene, not the box's motion, explains them: textured background). A plain background
                                 or a dark object's plain body says nothing either way and is not cut (a night car whose
                                 lights alone move, a uniform disc whose edge moves on one side only).""",
                                 valid=Valid.real(minimum=0, maximum=1))
    affine_reseat: float = param(1.5, """A young target's box (no time to contact yet; not a uniform region's, a shadow's
                                 or one cut by the border; at most twice ``max_shift`` across) is put, once, on the
                                 region that changed since ``change_frames`` before about its centre once the window's
                                 affine motion is undone (:func:`~mlplc2.targets.change.affine_change_box`, within
                                 ``max_shift``), its history carried (:meth:`Track.reseat`), where that region is this
                                 many times smaller (the square root of the areas), its centre lies in the box and it is
                                 no part of another target. The change box (step 2) undoes a shift of its window; under
                                 a camera that moves forward the background grows and shears there, and a small object's
                                 box takes much of it (a drone's collider 11 px wide in a box of 66 x 54 px: the box
                                 grows as the ground does, its time to contact 3 s at a true 0.9 s). On since session 29
                                 (docs/history.md, "The affine re-seat, bounded"; measured first in session 28, "A change
                                 box that undoes the window's affine motion"); 0 = off.""",
                                 valid=Valid.real(minimum=0))
    affine_reseat_max: float = param(4.0, """``affine_reseat`` puts no box on a region more than this many times
                                     smaller than the box (the square root of the areas): the region is then a part of
                                     the object that changed most, not the object (``ground_forward_3_h36``'s collider,
                                     39 x 74 px, put on 7 x 5 px and not warned; the drones' boxes that it fixes are 2-3
                                     times their region). 0 = no bound (docs/history.md, "The affine re-seat, bounded").""",
                                     valid=Valid.real(minimum=0))
    affine_inliers: float = param(0.8, """``affine_reseat`` puts a box only where at least this share of the corners
                                  followed fit one affine motion of the window: where depth varies across it (a
                                  dashcam's road, cars and roadside) no one motion is the background's, and the change
                                  left is no object's (the real clip ``sudden_turning_vehicle``'s collider lost at 0).""",
                                  valid=Valid.real(minimum=0, maximum=1))
    ground_change: bool = param(True, """With ``affine_reseat``, where the window's affine motion finds no box (the horizon
                                crosses it: the backdrop stands still above, the road streams below), a young
                                target's box that reaches below the heading's row is put on what changed against the
                                oldest kept frame with its ground carried into this frame's pixels, the ground plane
                                as it moves under a camera that translates towards the heading (one unknown, the
                                distance driven over the camera's height: :func:`~mlplc2.targets.change.ground_kappa`,
                                once a frame): the road does not change, what stands on it does; under the same bounds.
                                Where no ``kappa`` lowers the ground's change (no plane in view), nothing. On since
                                session 39 (docs/history.md, "The road carried as the ground plane" and "The road
                                carried, adopted"): the drive's false episodes over thirty-nine sets 104 -> 90; off:
                                the affine map alone.""", valid=Valid.boolean())
    ground_alarm: float = param(0.0, """With ``ground_change``, the field alarm without a course (no fit yet,
                                :func:`~mlplc2.targets.warning.alarm_warns`) is no evidence on a box at least half below
                                the horizon whose change there falls to less than this share of it once the oldest
                                kept frame's ground is carried: a patch of the road. 0.5 measured in session 38, not
                                adopted (it gave ``UAV_outdoor_1`` a false warning); 0 = off (the default).""",
                                valid=Valid.real(minimum=0, maximum=1))
    flat_onset: float = param(1.8, """From a translating camera (a measured heading, ``CameraMotion.heading``), a
                              warning does not begin on a box that holds the heading (:func:`~mlplc2.targets.warning.holds`)
                              and is more than this many times wider than tall (:func:`~mlplc2.targets.warning.flat`); once
                              a target has warned, it warns on whatever its box's shape. A roadside object that runs along
                              the path (a hedge, a wall, a row of parked cars) is seen in perspective reaching towards the
                              focus of expansion: its box spans the heading, flat, and expands about the heading as an
                              object on a collision course does, so its course is short (0.17-0.36 extents); the
                              colliders' first warnings on boxes that hold the heading are at most 1.70 times wider than
                              tall (the real clips': 1.65). 0 = off (1.8, the default since session 13: holdout 2's false
                              episodes per 1000 frames 1.24 -> 0.82 (0.38 -> 0.10 % of frames), holdout 3's 0.82 -> 0.72,
                              no collision, lead or real clip changed; docs/history.md, "A flat box across the path").""",
                              valid=Valid.real(minimum=0))
    reonset_miss: float = param(0.4, """A target that has warned and whose warning lapsed (its last frame was no warning)
                                warns again without a field of it in collision alarm this frame only on a course
                                (``miss``, this frame's or the one held) of at most this: its box has mostly slid off
                                its object by then (over a neighbour, a passing object or the background), and its
                                course straddles both; an object on a collision course whose warning lapsed for a
                                frame or two keeps its short course (the colliders' returns without an alarm: 0.09-0.25
                                extents, 0.59 and 0.87 on returns of targets that had warned on their collider
                                already). 0 = off (0.4, the default since session 13: the standard suite's false
                                episodes per 1000 frames 0.72 -> 0.41 (0.25 -> 0.15 % of frames), holdout 2's 0.82 -> 0.72 with
                                ``flat_onset``, no collision, lead or real clip changed; docs/history.md, "A flat box
                                across the path").""",
                                unit="object extents", valid=Valid.real(minimum=0))
    contact_blind: int = param(2, """Once a target warns on a box wider or taller than the frame (the object fills
                               the view: the camera is about to hit it), no other target begins a warning until
                               that target's predicted contact (this frame's ``ttc_s``) plus this many frames
                               (:func:`~mlplc2.targets.warning.blind_until`): the view is the colliding object, and
                               the seeds found on it then (its texture sweeping past, the target that held it lost)
                               are the same collision, scored off it (the truth has no box for it at contact). A
                               target that warned goes on; one that begins after the window is not held back. 0 =
                               off (2, the default since session 15: false episodes per 1000 frames 0.41 -> 0.31
                               standard, 0.93 -> 0.62 holdout 4, no collision, lead or real clip changed;
                               docs/history.md, "False warnings, session 15").""",
                               unit="frames", valid=Valid.integer(0))
    path_drift: float = param(0.4, """From a translating camera (a measured heading, ``CameraMotion.heading``), a
                              warning begins without a field of the target in collision alarm only on a box
                              that holds the heading or whose centre keeps its bearing: it drifted away from
                              the heading by at most this fraction of the static world's drift over the same
                              growth (:func:`~mlplc2.targets.warning.off_path`); where that drift is under
                              ``MIN_DRIFT_PX`` (a box that began at the heading), it moved away from the
                              heading by at most ``MIN_DRIFT_PX`` (session 11: sudden_turning_vehicle's
                              passing van). The static world beside the path expands about the heading (1),
                              an object on a collision course keeps its bearing (0). 0 = off (0.4, the
                              default since session 10: the drive scenes' false episodes 15.74 -> 10.19 per
                              1000 frames, holdout 10.19 -> 9.26, no collision or lead lost; docs/history.md,
                              "A warning that begins off the path").""",
                              valid=Valid.real(minimum=0))
    fresh_ttc: float = param(0.9, """From a translating camera (a measured heading), a warning begins without a field of
                             the target in collision alarm on a track whose first time to contact (of its own fit, or
                             of the lost track it was refound from) was under this only on a box that holds the heading
                             or whose centre drifted away from it by at most ``fresh_drift`` of the static world's
                             drift (:func:`~mlplc2.targets.warning.fresh`); a frame after a camera slower than
                             ``nominal_fps`` is spared. The road or ground beside a passing car, seeded near the
                             camera, first gets a time to contact already short; an object on a collision course is
                             mostly seen approaching from beyond the horizon, and one found that late keeps its
                             bearing. 0 = off (0.9, with ``fresh_drift`` 0.1 and ``fresh_miss`` 0.2, the default since
                             session 18: false episodes per 1000 frames holdout 1 0.82 -> 0.51, holdout 2 0.51 -> 0.10,
                             holdout 5 0.93 -> 0.82, holdout 6 1.24 -> 1.13, holdout 7 0.51 -> 0.31 (the drive's 47
                             episodes on the eleven sets -> 36); the standard suite, the real clips and their re-encoded
                             copies, holdouts 3, 4, 8, 9 and 10 as before; no collision, lead or real clip changed;
                             docs/history.md, "False warnings, session 18").""",
                             unit="s", valid=Valid.real(minimum=0))
    fresh_drift: float = param(0.1, """``fresh_ttc``'s largest drift away from the heading, as a fraction of the static
                               world's drift over the same growth (0: an object on a collision course, 1: the static
                               world; ``path_drift`` holds every other track to 0.4; one value tried, 0.1: the drive's
                               false boxes drifted 0.11-0.40, the one collider found that late and measured, -0.03).""",
                               valid=Valid.real(minimum=0))
    fresh_miss: float = param(0.2, """``fresh_ttc`` holds back only a box whose course (``miss``) misses by more than this
                              (none known: no test): an object on a course through the middle of the camera's extent
                              found that late may drift a little as the static world does (its drift is about its miss
                              over its offset from the heading: ``ground_forward_4_h8``'s collider, a course of 0.12,
                              drifted by 0.15 and warned 0.33 s later with 0; the drive's false boxes: courses
                              0.24-0.78).""", unit="object extents", valid=Valid.real(minimum=0))
    alarm_frames: int = param(2, """From a translating camera (a measured heading), the field alarm without a
                              course (no fit yet) begins a warning on a box that does not hold the heading only
                              once a field of the target has been in collision alarm this many processed
                              frames in a row (``Track.alarm_run``: a repeated frame the model holds is no
                              gap; :func:`~mlplc2.targets.warning.fleeting`): the static
                              world's alarms beside the path are fleeting. 1 = off (2, the default since
                              session 10: the drive scenes' false episodes 10.19 -> 5.56 per 1000 frames,
                              holdout 9.26 -> 7.41, no collision or clip lost, the real clips' leads
                              ``bear_attack`` 0.67 -> 0.57 s (0.60 s since session 11 counts processed frames), ``UAV_outdoor_1``
                              0.50 -> 0.47 s; docs/history.md,
                              "The field alarm on the static world").""", unit="frames", valid=Valid.integer(1))
    alarm_course: bool = param(True, """With ``alarm_frames`` > 1: the field alarm's first frame in a row begins a
                              warning on an alarm seed (a target born on it) without waiting when the course
                              of the seed's own alignment over ``change_frames`` (``Track.seed_move``;
                              :func:`~mlplc2.targets.warning.seed_course`) passes within ``max_miss``, as the
                              alarm with a fitted course does (issue 22 item 4: the real clips' warnings on
                              their field alarm's first frame; docs/history.md, "The field alarm's first frame
                              with the seed's course"). False = off (``alarm_frames`` alone).""",
                              valid=Valid.boolean())
    alarm_isotropic: bool = param(True, """From a translating camera (a measured heading), the field alarm without a
                              course does not begin a warning on a box that does not hold the heading when its
                              seed's own alignment over ``change_frames`` (``Track.seed_move``) fails the growth
                              test of every other seed: it grew by less than ``min_growth``, or unlike in both
                              directions (beyond ``max_anisotropy``): the ground, a wall along the path, the edge
                              where the static world's surfaces meet
                              (:func:`~mlplc2.targets.warning.anisotropic`); a track born before its alarm (no
                              seed alignment) is not tested. False = off (on since session 14: false episodes per
                              1000 frames holdout 1 1.24 -> 1.03, holdout 2 0.72 -> 0.51, the standard suite and
                              holdout 3 as before, no collision, lead or real clip changed; docs/history.md, "The
                              field alarm's seed that does not loom").""", valid=Valid.boolean())
    seed_return: float = param(0.5, """The seed's own alignment over ``change_frames`` (``Track.seed_move``: the
                              drift and growth that :func:`~mlplc2.targets.warning.keeps_bearing`,
                              ``alarm_isotropic``, ``alarm_course`` and ``split_bearing`` judge on a target's
                              first frame) counts only when the same alignment run backwards, from where it
                              ended to the frame ``change_frames`` before, comes back to within this fraction
                              of the box's smaller side (the forward-backward check of trackers); else the seed
                              has none, and ``alarm_isotropic`` counts it as a seed that did not loom. The road
                              just ahead of a car seen through a wide lens moves 20 px or more a frame, too far
                              for the alignment, which then settles on a shift and a growth that mean nothing
                              and made the field alarm warn there. The LPLC2 family's image alignment only (the
                              flow baseline's seed is its object flow, not checked). 0 = off (on since session
                              41; docs/history.md, "The seed's alignment checked backwards").""",
                              unit="box sides", valid=Valid.real(minimum=0))
    hold_frames: int = param(15, """A target whose fit gives no time to contact this frame (the growth not
                             significant, not isotropic, a gap in its measurement) reports its last one
                             counted down for up to this many frames after it (``Target.ttc_age_s``: its
                             age). It begins no warning; a running one goes on through such frames on it
                             (``warn_through``, ``through_alarm``). 0 = off (``docs/targets.md``, step 8).""",
                             unit="frames", valid=Valid.integer(0))
    refind_frames: int = param(15, """A new target whose centre lies in the last box (plus a quarter of its
                               size) of a target lost (dropped or merged) at most this many frames before,
                               and of a size within a factor of 3 of it, takes over its id, its last time to
                               contact (``hold_frames``) and its warning state (``warned``, a running or lapsed
                               warning):
                               one object, one id through a gap. 0 = off (``docs/targets.md``, step 8).""",
                               unit="frames", valid=Valid.integer(0))
    refind_late: int = param(45, """A new target whose box holds the last centre of a target lost (dropped or merged)
                             more than ``refind_frames`` and at most this many frames before, or absorbed
                             (``absorb_frames``), of a size within a factor of 4 of it, takes over its id and frame of
                             birth only (its warning state, last time to contact and history begin afresh; its age in
                             ``_merge`` stays its own): a far object lost while it did not grow measurably and found
                             again, grown, where it was. Labels only: every target's box, time to contact and warning
                             are those without it. 0 = off; 45 since session 16 (docs/history.md, "Targets per object,
                             session 16").""", unit="frames", valid=Valid.integer(0))
    absorb_frames: int = param(5, """A target warning this frame absorbs every other target whose centre lies in
                               its box plus a quarter of its size (as a field it would own) and that has had no
                               time to contact for this many frames (since its last one, or its birth): the
                               static world's box beside an object near contact is the object's (its fields go
                               to it; the absorbed one is not refound, but for its id by ``refind_late``). 0 = off; 5 since session 15 (docs/history.md,
                               "Targets per object, session 15", and "Session 15: the defaults measured together").""", unit="frames", valid=Valid.integer(0))
    passed_seeds: bool = param(True, """A target whose last time to contact has run out (its contact passed) with no
                               time to contact since no longer claims the LM and change seeds inside its box, for
                               good, its box spanning the view or not: no seed zone, and a box seeded there is not a
                               part of it (:meth:`TargetLayer._opened`). It keeps the
                               attention fields it owns (after a contact they are the collider's own) and counts
                               against ``max_targets``; a target born inside it (``Track.behind``) does not begin a
                               warning on the field alarm alone, without a course. On: two more collisions warned
                               (the standard suite, holdout 1), no false frame added on the four seed sets (only for
                               a box over the view: the same, with later leads). False = off (docs/history.md,
                               "Objects missed", session 14).""",
                               valid=Valid.boolean())
    refind_drift: float = param(0.4, """A target refound after a gap (``refind_frames``) whose lost track's centre drifted
                                away from the measured heading by more than this fraction of the static world's drift
                                (:func:`~mlplc2.targets.warning.drift`; the largest over the tracks it took over from)
                                does not begin a warning on the field alarm alone, without a course: the lost track
                                passed beside the path (a passing car leaving the view at the border, lost and found
                                again there), and the refound track's own history is too short to tell. 0 = off; 0.4
                                since session 15 (docs/history.md, "Objects missed", session 15).""",
                                valid=Valid.real(minimum=0))
    uniform_tol: float = param(4.0, """A candidate's first box is the uniform region beside its seed when there is one:
                               the pixels reached by a flood fill of at most this many grey levels from a start point
                               ``claim`` / 3, 2 ``claim`` / 3 or ``claim`` px from the seed (8 directions; the largest
                               region that passes ``uniform_fill``, is at least 8 px across, at most
                               ``uniform_aspect`` elongated and does not touch the frame's border). A uniform object
                               (issue 22: the black lead vehicle of the drive scenes) has no texture inside: its
                               local motion and change lie on its outline only, the seed on an edge or a corner, and
                               the change window (``max_shift``) is smaller than it, so the other boxes hold a part
                               of it plus road. The box is tried before the others (which follow when it does not
                               grow). 0 = off; 4 since session 15 (docs/history.md, "A uniform object's box", and "Objects missed",
                               session 15).""",
                               unit="grey levels", valid=Valid.real(minimum=0))
    uniform_fill: float = param(0.7, """``uniform_tol``: the smallest fraction of its bounding box a uniform region fills
                                (a compact object, not a patch of smooth texture). A rectangle fills all of it, a disc or
                                an ellipse pi/4 (0.785); counted in pixels a disc fills 0.76-0.81 (the benchmark's
                                rendered discs, 10-64 px across) or, drawn to whole pixels with single pixels at its
                                four tips, 0.72-0.77 from 20 px across: 0.7 takes round objects too. 0.85 until
                                session 48, which took no disc: a bright disc over the walked ground was boxed with
                                the ground below it and warned late or never (docs/history.md, "A round object's
                                box").""",
                                valid=Valid.real(minimum=0, maximum=1))
    uniform_aspect: float = param(2.0, """``uniform_tol``: the largest elongation (longer side / shorter side) of a
                                  uniform region's box (not a band of the horizon or a wall).""",
                                  valid=Valid.real(minimum=1))
    uniform_lm: bool = param(True, """``uniform_tol`` for the LM and change seeds too; False = only for the seed of an attention
                             field (Eq. 13-16: looming evidence of its own).""", valid=Valid.boolean())
    uniform_reseat: bool = param(True, """A target seeded on a uniform region (``uniform_tol``) is put back on that region each
                                 frame it is followed (:meth:`Track.reseat`, its history carried): the uniform
                                 region at its centre, when it is a compact object (``uniform_fill``,
                                 ``uniform_aspect``; at the frame's border its visible part) whose centre lies inside the box and
                                 whose area is within a factor 2 of the box's. The alignment's patch holds the
                                 object's outline and the road around it, which flows faster than the object: the
                                 box grows taller than its object and slides off it (the drive scenes' lead
                                 vehicle). False = off; on since session 15 (docs/history.md, "A uniform object's box").""",
                                 valid=Valid.boolean())
    uniform_growth: bool = param(True, """With ``uniform_reseat``, a re-seated box's growth is its uniform region's: the
                                 accumulated log-scale and log-anisotropy of the newest observation are those of the
                                 last region measured (not cut by the border) plus the log of the region's mean
                                 and relative size change since (the sum telescopes: the object's size to a pixel),
                                 in place of the image alignment's, whose patch holds road that flows faster than
                                 the object (a box anisotropic a second before contact). False = off; on since session 15.""",
                                 valid=Valid.boolean())
    uniform_spread: bool = param(True, """In short: a plain-coloured object's growth is measured from its whole area, edge
                                 pixels counted by how much of them it covers, not from its box. In full: with
                                 ``uniform_growth``, the region's size is its spread (the standard deviations of its
                                 pixels' columns and rows, its 1-px rim weighted by its coverage between the region's
                                 and the background's grey levels: :func:`~mlplc2.targets.change.uniform_spread`), not
                                 its bounding box, which grows by whole pixels (a 20-px disc 19 -> 21 px in a frame)
                                 and lapses the fit on single frames. False = the box (docs/history.md, "A round
                                 object's growth, from its area").""", valid=Valid.boolean())
    idle_frames: int = param(30, "Frames without an estimate or an answering field after which a target is dropped.",
                             unit="frames", valid=Valid.integer(0))

    def span(self, frames: float, fps: float) -> float:
        """``frames`` frames at ``nominal_fps`` as a span of the model's clock (frame intervals at ``fps``)."""
        return frames * fps / self.nominal_fps

    def __post_init__(self) -> None:
        check_fields(self, "TargetParams")
        if self.min_frames > self.window:
            raise InputValueError(f"TargetParams.min_frames must be <= window ({self.window}), "
                                  f"got {self.min_frames!r}")

