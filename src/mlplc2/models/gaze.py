"""Gaze stabilisation's share of the models that stabilise (the LPLC2 family with ``stabilise=True``, the
optical-flow baseline; docs/model.md, "Camera motion"): a gyro's angular velocity, given to
:meth:`~mlplc2.models.base.Model.step` each frame, integrated into the camera's rotation since the last
processed frame (:attr:`GazeStabilisation.rotation_given`), and the camera's turn each processed frame
(:meth:`GazeStabilisation._turn`). The LGMD models do not stabilise: they take no gyro
(:meth:`~mlplc2.models.base.Model.gyro_refusal`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["GazeStabilisation"]


class GazeStabilisation:
    """Mixin of the models that stabilise their gaze, listed before :class:`~mlplc2.models.base.Model` in
    their bases (``class MyModel(GazeStabilisation, Model)``). The model sets ``stabilise``, ``hfov_deg`` and,
    where it stabilises, ``_camera`` (a :class:`mlplc2.camera.MotionEstimator`); ``_layer``, where it has one,
    gets the camera's heading."""

    def _forget(self) -> None:
        super()._forget()
        self._turned: np.ndarray | None = np.zeros(3)   # gyro rotation (rad) since the last processed frame
        self._rate: np.ndarray | None = None            # the gyro's rate (rad/s) at the last frame
        self.rotation_given: tuple[float, float, float] | None = None
        """The camera's rotation (rad, its axes) since the last processed frame from the gyro given
        to :meth:`step` (held frames' included), or None: estimated from the images."""

    def gyro_refusal(self) -> str | None:
        """None where the model stabilises (``stabilise``) and knows its field of view (``hfov_deg``), else why not."""
        if not self.stabilise:
            return f"model {self.name!r} does not stabilise its gaze (stabilise=False): it takes no gyro"
        if self.hfov_deg is None:
            return "a gyro needs the camera's field of view (hfov_deg) to turn its rotation into pixels"
        return None

    def _see_gyro(self, rate: np.ndarray | None, dt: float | None, processed: bool) -> None:
        """Add the gyro's turn since the last frame (trapezoid over ``dt`` seconds; None: the first frame)
        to the rotation since the last processed frame; a frame without a gyro leaves it unknown. On a
        processed frame that rotation becomes :attr:`rotation_given` (None without this frame's gyro) and
        starts again from zero."""
        if rate is None:
            self._turned = None
        elif dt is not None and self._turned is not None:
            self._turned = self._turned + (rate if self._rate is None else 0.5 * (rate + self._rate)) * dt
        self._rate = rate
        if processed:
            self.rotation_given = None if self._turned is None or rate is None else tuple(float(v) for v in self._turned)
            self._turned = np.zeros(3)

    def _turn(self, image: np.ndarray, shape: tuple[int, int]):
        """Gaze stabilisation's first step, one for every model that stabilises (docs/model.md, "Camera
        motion"): this frame's camera motion (``self.camera_motion``) from ``image`` by the model's
        ``_camera`` (:class:`mlplc2.camera.MotionEstimator`; the gyro's rotation where given), whose heading
        the target layer (``_layer``, where the model has one) takes for the course; returns the homography
        that carries the last frame's pixels into this one's, None where the camera did not turn."""
        self.camera_motion, hom = self._camera.turn(image, shape, hfov_deg=self.hfov_deg,
                                                    heading=self._work_heading(), omega=self.rotation_given)
        layer = getattr(self, "_layer", None)
        if layer is not None:                              # the course's heading (docs/targets.md, step 7)
            layer.see_heading(self.camera_motion.heading, self.camera_motion.heading_confidence)
        return hom
