"""Drawing the 3-D approaches: textures, background, ground plane, objects, optics and noise.

Every pixel's ray is intersected with the object's plane (a homography per
object and frame, evaluated only in the object's bounding box) on a
``supersample x supersample`` grid of sub-pixel samples; each sample counts the
share of its cell inside the outline (from its signed distance to it, exact for
a straight edge) and their mean is the pixel's coverage, so sub-pixel growth
shows as grey-level changes (:func:`draw_object`). Objects are drawn far to near
(painter's order by the depth Z of their centre); an object is drawn until it
reaches the camera plane (contact) while its centre is in front of the camera
and nearer than :data:`~mlplc2.stimuli.world.geometry.FAR_M`. Textured objects
carry a :func:`~mlplc2.stimuli.procedural_background` pattern fixed on the
object, sampled through the projection from a box-filter mip-map
(:func:`mipmap`). Backgrounds (:class:`Background`): ``"plain"``
(:func:`mlplc2.stimuli.plain_level`), ``"texture"`` (a procedural texture at
infinity, a panorama sampled by ray direction: it moves only when the camera
turns) and ``"ground"`` (:class:`Ground`: a textured ground plane
``camera_height_m`` below the camera under the far texture, each pixel's ray
intersected with the plane and filtered by its footprint, so the far ground
blurs instead of aliasing). Then optional optics blur (``blur_px``, Gaussian
sigma) and sensor noise (``noise_std`` grey levels), rounded to ``uint8``
(:func:`render`). Every random draw has its own seed, :func:`sub_seed` of the
scene's seed and a key (1 panorama, 2 ground, 3 object textures, 4 noise).
"""

from __future__ import annotations

import math

import numpy as np

from .._common import plain_level, procedural_background
from .camera import Camera
from .geometry import ObjectGeometry

__all__ = ["render", "draw_object", "Background", "Ground", "mipmap", "object_texture", "sub_seed",
           "APPROACH_BACKGROUNDS", "OBJECT_TEXTURE_PX", "GROUND_TEXTURE_PX", "GROUND_TEXEL_M", "GROUND_SUBROWS"]

#: Backgrounds of :func:`mlplc2.stimuli.world.approach`.
APPROACH_BACKGROUNDS: tuple[str, ...] = ("plain", "texture", "ground")
#: Side (texels, a power of 2) of an object's own texture, mapped onto its width.
OBJECT_TEXTURE_PX = 128
#: Side (texels, a power of 2) of the ground texture and its scale (m per texel). The texture is
#: periodic (``procedural_background(..., periodic=True)``) and tiles the plane every
#: 1024 x 0.01 = 10.24 m without seams.
GROUND_TEXTURE_PX = 1024
GROUND_TEXEL_M = 0.01
#: Sub-rows per pixel row on which the ground is sampled.
GROUND_SUBROWS = 4
#: Extra panorama margin (px) around the directions the camera sees.
_PANORAMA_MARGIN = 4


# ---------------------------------------------------------------------------
# The video
# ---------------------------------------------------------------------------

def render(geos: list[ObjectGeometry], cam: Camera, background: str, seed: int, ss: int, blur: float,
           noise: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """The ``uint8 (T, H, W)`` video of the objects ``geos`` over ``background`` and, per object,
    whether it covers any sub-pixel sample in each of its frames (from its onset)."""
    import cv2

    objects = [g.obj for g in geos]
    level = plain_level([o.appearance for o in objects])
    bg = Background(background, cam, level, seed)
    textures = [object_texture(o.seed if o.seed is not None else sub_seed(seed, 3, i))
                if o.appearance == "textured" else None for i, o in enumerate(objects)]
    levels = [0.0 if o.appearance == "dark" else 255.0 for o in objects]
    visible = [np.zeros(len(g.frames), bool) for g in geos]
    video = np.empty((cam.n, cam.h, cam.w), np.uint8)
    rng = np.random.default_rng(sub_seed(seed, 4))
    for k in range(cam.n):
        img = bg.frame(k)
        alive = [(g.P[k - g.obj.onset, 2], i) for i, g in enumerate(geos)
                 if k >= g.obj.onset and g.drawn[k - g.obj.onset]]
        for _, i in sorted(alive, reverse=True):          # far to near
            j = k - geos[i].obj.onset
            visible[i][j] = draw_object(img, geos[i], j, ss, levels[i], textures[i])
        if blur > 0:
            img = cv2.GaussianBlur(img, (0, 0), blur)
        if noise > 0:
            img = img + rng.normal(0.0, noise, img.shape).astype(np.float32)
        np.rint(np.clip(img, 0, 255), out=img)
        video[k] = img
    return video, visible


# ---------------------------------------------------------------------------
# Textures
# ---------------------------------------------------------------------------

def object_texture(seed: int) -> list[np.ndarray]:
    """The mip-map of an object's own procedural texture (:data:`OBJECT_TEXTURE_PX` square)."""
    return mipmap(procedural_background(OBJECT_TEXTURE_PX, OBJECT_TEXTURE_PX, seed))


def sub_seed(seed: int, *key: int) -> int:
    """An independent 32-bit seed for one purpose of a scene."""
    return int(np.random.SeedSequence([seed, *key]).generate_state(1)[0])


def mipmap(texture: np.ndarray) -> list[np.ndarray]:
    """Box-filter pyramid (2 x 2 means) of a power-of-2 square texture, down to 1 x 1."""
    levels = [np.asarray(texture, np.float32)]
    while levels[-1].shape[0] > 1:
        t = levels[-1]
        n = t.shape[0] // 2
        levels.append(t.reshape(n, 2, n, 2).mean(axis=(1, 3)))
    return levels


def _sample(tex: np.ndarray, mx: np.ndarray, my: np.ndarray, *, wrap: bool = False) -> np.ndarray:
    """Bilinear samples of ``tex`` at the points ``(mx, my)`` (1-D, texel centres at integers;
    beyond the border the texture repeats if ``wrap``, else is mirrored)."""
    import cv2

    n = mx.size
    cols = 4096                                  # cv2.remap: fewer than 32767 columns
    rows = -(-n // cols)
    grid = []
    for m, size in ((mx, tex.shape[1]), (my, tex.shape[0])):
        g = np.zeros(rows * cols, np.float32)
        g[:n] = m
        if wrap:   # into [0, size): cv2.remap is many times faster inside the texture
            g -= np.float32(size) * np.floor(g * np.float32(1.0 / size))
        grid.append(g.reshape(rows, cols))
    border = cv2.BORDER_WRAP if wrap else cv2.BORDER_REFLECT
    return cv2.remap(tex, grid[0], grid[1], cv2.INTER_LINEAR, borderMode=border).ravel()[:n]


# ---------------------------------------------------------------------------
# Backgrounds
# ---------------------------------------------------------------------------

class Background:
    """Renders the background of each frame (float32 ``(H, W)``)."""

    def __init__(self, kind: str, cam: Camera, level: float, seed: int):
        import cv2

        self.cv2 = cv2
        self.kind, self.cam, self.level = kind, cam, level
        self.cache: np.ndarray | None = None          # the last frame (reused while nothing moves)
        self.sky: np.ndarray | None = None            # the far texture of the last frame
        self.maps = None                              # panorama coordinates of the pixels
        w, h = cam.w, cam.h
        self.rays = cam.rays(np.arange(w, dtype=np.float64)[None, :],
                             np.arange(h, dtype=np.float64)[:, None])      # (H, W, 3)
        if kind in ("texture", "ground"):
            # panorama: azimuth x elevation at f px per radian, covering every direction seen
            border = np.concatenate([self.rays[0], self.rays[-1], self.rays[:, 0], self.rays[:, -1]])
            if cam.motion == "path":
                rots = cam.R
            else:
                angles = np.unique(np.concatenate([cam.angle[[0, -1]], cam.angle[::max(1, cam.n // 64)]]))
                rots = cam.rotation(angles)
            az, el = self._angles(np.einsum("aij,pj->api", rots, border))
            m = _PANORAMA_MARGIN / cam.f
            self.az0, self.el0 = az.min() - m, el.min() - m
            pw = int(math.ceil((az.max() - az.min()) * cam.f)) + 2 * _PANORAMA_MARGIN + 2
            ph = int(math.ceil((el.max() - el.min()) * cam.f)) + 2 * _PANORAMA_MARGIN + 2
            self.panorama = procedural_background(pw, ph, sub_seed(seed, 1)).astype(np.float32)
        self.ground = Ground(cam, sub_seed(seed, 2)) if kind == "ground" else None

    @staticmethod
    def _angles(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.arctan2(d[..., 0], d[..., 2]), np.arctan2(d[..., 1], np.hypot(d[..., 0], d[..., 2]))

    def frame(self, k: int) -> np.ndarray:
        """A new float32 ``(H, W)`` background of frame ``k``."""
        cam = self.cam
        if self.kind == "plain":
            return np.full((cam.h, cam.w), self.level, np.float32)
        rotating = cam.motion in ("pan", "tilt", "path")
        if self.cache is not None and not rotating and not (self.ground and cam.motion == "forward"):
            return self.cache.copy()                       # nothing in the background moves
        if self.sky is None or rotating:
            if self.maps is None or cam.motion in ("tilt", "path"):
                rot = cam.R[k] if cam.motion == "path" else cam.rotation(cam.angle[k])
                az, el = self._angles(self.rays @ rot.T)     # world directions
                self.maps = (((az - self.az0) * cam.f).astype(np.float32),
                             ((el - self.el0) * cam.f).astype(np.float32), cam.angle[k])
            mx, my, angle = self.maps
            if cam.motion == "pan":          # panning adds to every direction's azimuth
                mx = mx + np.float32((cam.angle[k] - angle) * cam.f)
            self.sky = self.cv2.remap(self.panorama, mx, my, self.cv2.INTER_LINEAR,
                                      borderMode=self.cv2.BORDER_REFLECT)
        img = self.ground.render(self.sky, k) if self.ground else self.sky.copy()
        self.cache = img.copy()
        return img


class Ground:
    """A textured ground plane ``camera_height_m`` below the camera (Y = +height).

    Each pixel is sampled on :data:`GROUND_SUBROWS` sub-rows (the ground's footprint is longest
    along the image's columns); every sample's ray is intersected with the plane, and the
    periodic texture is read from the box-filter mip-map at the level of the sample's footprint
    (the larger of the pixel's extent along x and the sub-row's along y, in texels, measured on
    the pixel's middle sub-row; trilinear interpolation), so the far ground blurs instead of
    aliasing. Samples whose ray does not
    reach the ground (above the horizon) keep the far texture; the sub-row mean also
    anti-aliases the horizon. The rays, footprints and levels are computed once, except for a
    tilting camera: moving forward only shifts the ground points, panning turns them about
    the vertical axis (the footprints do not change).
    """

    def __init__(self, cam: Camera, seed: int):
        self.cam = cam
        self.levels = mipmap(procedural_background(GROUND_TEXTURE_PX, GROUND_TEXTURE_PX, seed, periodic=True))
        sub = (np.arange(GROUND_SUBROWS) + 0.5) / GROUND_SUBROWS - 0.5
        ys = (np.arange(cam.h)[:, None] + sub[None, :]).ravel()[:, None]
        # float32: the ground points need no more (the far ones read coarse levels), at half the cost
        self.rays = cam.rays(np.arange(cam.w, dtype=np.float64)[None, :], ys).astype(np.float32)
        self.plan = None

    def _setup(self, rot: np.ndarray, height: float | None = None) -> None:
        """Ground points (texels from the camera), mip-map levels and weights of the samples."""
        cam = self.cam
        d = self.rays @ rot.T.astype(np.float32)
        below = d[..., 1] > 1e-6
        height = cam.height if height is None else height
        s = np.float32(height / GROUND_TEXEL_M) / np.where(below, d[..., 1], np.nan)   # ray length, texels
        gx = s * d[..., 0]
        gz = s * d[..., 2]
        # footprint per pixel (from its middle sub-row) along x and per sub-row along y
        S = GROUND_SUBROWS
        px, pz = gx[S // 2::S], gz[S // 2::S]
        with np.errstate(invalid="ignore"):
            fx = np.hypot(np.diff(px, axis=1), np.diff(pz, axis=1))
            fy = np.hypot(np.diff(px, axis=0), np.diff(pz, axis=0)) / S
        fx = np.concatenate([fx, fx[:, -1:]], axis=1) if cam.w > 1 else np.full(px.shape, np.nan, np.float32)
        fy = np.concatenate([fy, fy[-1:]], axis=0) if cam.h > 1 else np.full(px.shape, np.nan, np.float32)
        top = len(self.levels) - 1
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.repeat(np.clip(np.log2(np.fmax(fx, fy)), 0.0, float(top)), S, axis=0)
        idx = np.flatnonzero(below)
        lam = lam.ravel()[idx]
        lam[~np.isfinite(lam)] = top                                  # next to the horizon
        lo = np.floor(lam).astype(np.int64)
        frac = (lam - lo).astype(np.float32)
        # each sample reads two levels; group the reads by level
        which = np.concatenate([np.arange(idx.size), np.arange(idx.size)])
        level = np.concatenate([lo, np.minimum(lo + 1, top)])
        weight = np.concatenate([1.0 - frac, frac])
        keep = weight > 0
        which, level, weight = which[keep], level[keep], weight[keep]
        order = np.argsort(level, kind="stable")
        bounds = np.searchsorted(level[order], np.arange(top + 2))
        groups = []
        for lv in range(top + 1):
            j = order[bounds[lv]:bounds[lv + 1]]
            if j.size:
                groups.append((lv, which[j], weight[j]))
        self.plan = (idx, gx.ravel()[idx], gz.ravel()[idx], groups)

    def render(self, sky: np.ndarray, k: int) -> np.ndarray:
        cam = self.cam
        if cam.motion == "path":     # the whole rotation, and the height the shake leaves
            self._setup(cam.R[k], cam.height - cam.position[k, 1])
        elif self.plan is None or cam.motion == "tilt":
            self._setup(cam.rotation(cam.angle[k] if cam.motion == "tilt" else 0.0))
        idx, gx, gz, groups = self.plan
        if cam.motion == "pan":
            c, s = math.cos(cam.angle[k]), math.sin(cam.angle[k])
            gx, gz = c * gx + s * gz, c * gz - s * gx
        ox, oz = cam.position[k, 0] / GROUND_TEXEL_M, cam.position[k, 2] / GROUND_TEXEL_M
        acc = np.zeros(idx.size, np.float32)
        for level, which, weight in groups:
            tex = self.levels[level]
            n = tex.shape[0]
            scale = 2.0 ** -level        # level-0 texel t -> level texel t * scale - (1 - scale) / 2
            # the camera's offset is wrapped into one period first (float64): the texture tiles
            mx = gx[which] * scale + ((ox * scale) % n - 0.5 * (1.0 - scale))
            mz = gz[which] * scale + ((oz * scale) % n - 0.5 * (1.0 - scale))
            acc[which] += weight * _sample(tex, mx, mz, wrap=True)    # a sample once per level
        sub = np.repeat(sky, GROUND_SUBROWS, axis=0)
        sub.ravel()[idx] = acc
        return sub.reshape(cam.h, GROUND_SUBROWS, cam.w).mean(axis=1)


# ---------------------------------------------------------------------------
# Objects on one frame
# ---------------------------------------------------------------------------

def draw_object(img: np.ndarray, geo: ObjectGeometry, j: int, ss: int, level: float,
          texture: list[np.ndarray] | None) -> bool:
    """Composite object ``geo`` at its frame index ``j`` onto ``img`` (in place); True if it
    covers any sub-pixel sample of the image."""
    import cv2

    h, w = img.shape
    if geo.whole[j]:
        x0, x1, y0, y1 = geo.box[j]
        i0, i1 = max(0, int(math.floor(x0))), min(w - 1, int(math.ceil(x1)))
        r0, r1 = max(0, int(math.floor(y0))), min(h - 1, int(math.ceil(y1)))
        if i0 > i1 or r0 > r1:
            return False
    else:
        i0, i1, r0, r1 = 0, w - 1, 0, h - 1
    nx, ny = i1 - i0 + 1, r1 - r0 + 1
    offs = (np.arange(ss, dtype=np.float64) + 0.5) / ss - 0.5
    xs = (np.arange(i0, i1 + 1, dtype=np.float64)[:, None] + offs[None, :]).ravel()[None, :]
    ys = (np.arange(r0, r1 + 1, dtype=np.float64)[:, None] + offs[None, :]).ravel()[:, None]
    hi = geo.Hinv[j]
    den = (hi[2, 0] * xs + hi[2, 2]) + hi[2, 1] * ys
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(den > 0, 1.0 / den, np.nan)
        u = ((hi[0, 0] * xs + hi[0, 2]) + hi[0, 1] * ys) * inv
        v = ((hi[1, 0] * xs + hi[1, 2]) + hi[1, 1] * ys) * inv
        r = geo.r
        dist = np.hypot(u, v) if geo.obj.shape == "disc" else np.maximum(np.abs(u), np.abs(v))
        # each sample's share of its own cell (1/ss px wide) inside the outline, from its signed
        # distance to the outline: exact for a straight edge, so coverage changes smoothly
        sub = np.clip(0.5 - (dist - r) * (geo.px_per_m[j] * ss), 0.0, 1.0)
    sub = np.nan_to_num(sub, nan=0.0).astype(np.float32)
    if not sub.any():
        return False
    cover = sub.reshape(ny, ss, nx, ss).mean(axis=(1, 3))
    if texture is None:
        patch = img[r0:r1 + 1, i0:i1 + 1]
        patch += (np.float32(level) - patch) * cover
        return True
    # textured: sample the object's mip-map level whose texels match the sub-pixel samples
    wpx = geo.width[j] if np.isfinite(geo.width[j]) else float(w)
    lvl = int(np.clip(math.floor(math.log2(max(OBJECT_TEXTURE_PX / max(wpx * ss, 1e-9), 1.0))), 0,
                      len(texture) - 1))
    tex = texture[lvl]
    n = tex.shape[0]
    inside = sub > 0
    mx = np.where(inside, (u / (2 * r) + 0.5) * n - 0.5, 0.0).astype(np.float32)
    my = np.where(inside, (v / (2 * r) + 0.5) * n - 0.5, 0.0).astype(np.float32)
    vals = cv2.remap(tex, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    paint = (vals * sub).reshape(ny, ss, nx, ss).mean(axis=(1, 3))
    patch = img[r0:r1 + 1, i0:i1 + 1]
    patch *= 1.0 - cover
    patch += paint
    return True
