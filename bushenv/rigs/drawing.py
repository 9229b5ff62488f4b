"""Drawing for ``render()``: a pygame canvas (``rgb_array`` frames or a ``human`` window) and
a ring of recent samples for the traces."""

from __future__ import annotations

import math
import time

import numpy as np


class Canvas:
    """A pygame surface for ``rgb_array`` frames, or a window for ``human``."""

    def __init__(self, width: int, height: int, render_mode: str, fps: float, title: str) -> None:
        import pygame

        self.pygame = pygame
        self.width, self.height = width, height
        self.render_mode = render_mode
        self.fps = fps
        pygame.font.init()
        self.font = pygame.font.Font(None, 20)
        self.small = pygame.font.Font(None, 16)
        if render_mode == "human":
            pygame.display.init()
            pygame.display.set_caption(title)
            self.window = pygame.display.set_mode((width, height))
        else:
            self.window = None
        self.surface = pygame.Surface((width, height))
        self._due_s: float | None = None  # when the next "human" frame is due (perf_counter)

    def clear(self) -> None:
        self.surface.fill((250, 250, 247))

    def line(self, p, q, color, width=2) -> None:
        self.pygame.draw.line(self.surface, color, _ipt(p), _ipt(q), width)

    def lines(self, points, color, width=1) -> None:
        if len(points) > 1:
            self.pygame.draw.lines(self.surface, color, False, [_ipt(p) for p in points], width)

    def rect(self, x, y, w, h, color, width=0) -> None:
        self.pygame.draw.rect(self.surface, color, (int(x), int(y), int(w), int(h)), width)

    def circle(self, c, r, color, width=0) -> None:
        self.pygame.draw.circle(self.surface, color, _ipt(c), int(r), width)

    def polygon(self, points, color, width=0) -> None:
        self.pygame.draw.polygon(self.surface, color, [_ipt(p) for p in points], width)

    def text(self, s, p, color=(30, 30, 30), small=False) -> None:
        font = self.small if small else self.font
        self.surface.blit(font.render(s, True, color), _ipt(p))

    def arrow(self, p, q, color, width=3) -> None:
        """An arrow from p to q (pixels); nothing if shorter than 2 px."""
        dx, dy = q[0] - p[0], q[1] - p[1]
        n = math.hypot(dx, dy)
        if n < 2:
            return
        ux, uy = dx / n, dy / n
        head = min(10.0, 0.5 * n)
        self.line(p, q, color, width)
        left = (q[0] - head * ux + 0.5 * head * uy, q[1] - head * uy - 0.5 * head * ux)
        right = (q[0] - head * ux - 0.5 * head * uy, q[1] - head * uy + 0.5 * head * ux)
        self.polygon([q, left, right], color)

    def force_bar(self, x, y, w, h, value, limit, color, label) -> None:
        """A horizontal bar centred at x + w/2: value / limit of the half width, clipped."""
        self.rect(x, y, w, h, (225, 225, 222))
        mid = x + w / 2
        frac = value / limit if math.isfinite(value) else (1.0 if value > 0 else -1.0)
        frac = max(-1.0, min(1.0, frac)) if math.isfinite(frac) else 0.0
        length = frac * w / 2
        self.rect(min(mid, mid + length), y, abs(length), h, color)
        self.line((mid, y - 2), (mid, y + h + 2), (90, 90, 90), 1)
        self.text(label, (x, y - 16), small=True)

    def frame(self) -> np.ndarray | None:
        pygame = self.pygame
        if self.render_mode == "human":
            pygame.event.pump()
            self.window.blit(self.surface, (0, 0))
            pygame.display.flip()
            self._pace()
            return None
        return np.transpose(np.array(pygame.surfarray.pixels3d(self.surface)), (1, 0, 2)).copy()

    def _pace(self) -> None:
        """Show frames ``fps`` per second of wall time: the simulated time in real time.
        (pygame's Clock.tick waits whole milliseconds: 4 ms for 204.8 fps, 20 % fast.) A
        frame that is late starts the schedule again instead of rushing to catch up."""
        now = time.perf_counter()
        due = now if self._due_s is None else self._due_s + 1.0 / self.fps
        if due > now:
            time.sleep(due - now)
        self._due_s = max(due, now)

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None


def _ipt(p) -> tuple[int, int]:
    return int(round(p[0])), int(round(p[1]))


class Trace:
    """A fixed-size ring of the last ``n`` samples of a few channels (for drawing only), so a
    long rollout keeps memory flat."""

    def __init__(self, channels: int, n: int = 256) -> None:
        self.buf = np.zeros((channels, n))
        self.n = n
        self.count = 0

    def clear(self) -> None:
        self.buf[:] = 0.0
        self.count = 0

    def push(self, *values: float) -> None:
        i = self.count % self.n
        for c, v in enumerate(values):
            self.buf[c, i] = v
        self.count += 1

    def ordered(self) -> np.ndarray:
        """(channels, m) oldest first, m = min(count, n)."""
        m = min(self.count, self.n)
        if self.count <= self.n:
            return self.buf[:, :m]
        i = self.count % self.n
        return np.concatenate([self.buf[:, i:], self.buf[:, :i]], axis=1)


def plot_traces(canvas: Canvas, box, trace: Trace, scales, colors, labels) -> None:
    """Draw trace channels in a box (x, y, w, h), each scaled to +-scale of the half height."""
    x0, y0, w, h = box
    canvas.rect(x0, y0, w, h, (238, 238, 234))
    canvas.line((x0, y0 + h / 2), (x0 + w, y0 + h / 2), (180, 180, 180), 1)
    data = trace.ordered()
    m = data.shape[1]
    if m >= 2:
        xs = x0 + np.arange(m) * (w / (trace.n - 1))
        for c in range(data.shape[0]):
            ys = y0 + h / 2 - np.clip(np.nan_to_num(data[c] / scales[c]), -1, 1) * (h / 2 - 2)
            canvas.lines(list(zip(xs, ys, strict=True)), colors[c], 2)
    for i, (lab, col) in enumerate(zip(labels, colors, strict=True)):
        canvas.text(lab, (x0 + 6 + (w / len(labels)) * i, y0 + 4), col, small=True)
