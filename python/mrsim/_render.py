"""A cheap top-down picture of a :class:`mrsim.Sim` as an RGB array."""

import numpy as np

_BACKGROUND = (255, 255, 255)
_ROBOT = (70, 110, 200)
_LEARNER = (220, 60, 50)
_OBSTACLE = (120, 120, 120)
_PERSON = (244, 164, 96)
_GOAL = (40, 170, 70)
_WALL = (0, 0, 0)


class Canvas:
    """Maps the scene's extent (walls, starts and goals) onto ``size`` pixels."""

    def __init__(self, sim, size: int = 256):
        pts = [sim.positions(), sim.goals()]
        walls = sim.walls()
        if len(walls):
            pts += [walls[:, :2], walls[:, 2:]]
        pts = np.concatenate(pts)
        margin = float(sim.radii().max(initial=0.0)) + 0.5
        self.lo = pts.min(axis=0) - margin
        span = float((pts.max(axis=0) + margin - self.lo).max())
        self.scale = (size - 1) / span
        self.size = size

    def _px(self, p):
        x = (p[..., 0] - self.lo[0]) * self.scale
        y = (self.size - 1) - (p[..., 1] - self.lo[1]) * self.scale
        return x, y

    def draw(self, sim) -> np.ndarray:
        n = self.size
        img = np.empty((n, n, 3), dtype=np.uint8)
        img[:] = _BACKGROUND
        yy, xx = np.mgrid[0:n, 0:n]
        learners = set(sim.learner_indices)
        for g in sim.goals():
            self._disc(img, xx, yy, g, 0.15, _GOAL)
        pos, radii, kinds = sim.positions(), sim.radii(), sim.kinds()
        for i, (p, r, kind) in enumerate(zip(pos, radii, kinds)):
            if kind == 1:
                colour = _OBSTACLE
            elif kind == 2:
                colour = _PERSON
            else:
                colour = _LEARNER if i in learners else _ROBOT
            self._disc(img, xx, yy, p, max(r, 0.05), colour)
        for w in sim.walls():
            a, b = w[:2], w[2:]
            steps = int(np.hypot(*(b - a)) * self.scale) + 2
            t = np.linspace(0.0, 1.0, steps)[:, None]
            x, y = self._px(a + (b - a) * t)
            ok = (x >= 0) & (x < n) & (y >= 0) & (y < n)
            img[y[ok].astype(int), x[ok].astype(int)] = _WALL
        return img

    def _disc(self, img, xx, yy, centre, radius, colour):
        cx, cy = self._px(np.asarray(centre, dtype=float))
        rp = radius * self.scale
        x0, x1 = int(max(cx - rp, 0)), int(min(cx + rp + 1, self.size))
        y0, y1 = int(max(cy - rp, 0)), int(min(cy + rp + 1, self.size))
        if x0 >= x1 or y0 >= y1:
            return
        sub = (xx[y0:y1, x0:x1] - cx) ** 2 + (yy[y0:y1, x0:x1] - cy) ** 2 <= rp * rp
        img[y0:y1, x0:x1][sub] = colour


class Drawn:
    """``render()`` of an env over one :class:`mrsim.Sim` (``self._sim``),
    drawn on a canvas made at the first call."""

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._canvas is None:
            self._canvas = Canvas(self._sim, self._render_size)
        return self._canvas.draw(self._sim)
