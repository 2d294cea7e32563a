"""The panel drawn over each video frame: time, the link's state, and the last five
seconds of phi (true and estimated) and of the two photodiode powers."""

from __future__ import annotations

from collections import deque

import numpy as np
from PIL import Image, ImageDraw, ImageFont

#: Overlay badge of the link supervisor's state: text and colour.
STATUS_BADGES = {"ok": ("LINK OK", (90, 220, 120)),
                 "converging": ("ACQUIRING", (150, 200, 255)),
                 "dropout": ("BEAM BLOCKED - holding", (240, 210, 70)),
                 "lost": ("LINK LOST", (255, 170, 60)),
                 "scanning": ("LINK LOST - scanning", (255, 90, 90))}

TEXT = (230, 230, 230)
GRID = (70, 85, 95)
TRUE, ESTIMATE, P2 = (255, 255, 255), (80, 200, 255), (255, 170, 60)
#: A pan-tilt head's elevation, true and estimated.
ELEVATION, ELEVATION_ESTIMATE = (120, 230, 120), (255, 110, 200)


def axis_limits(values, base: tuple[float, float], step: float) -> tuple[float, float]:
    """``base``, widened in whole ``step``s only as far as the data needs: the scale
    stays put while the data fits, so a small wobble looks small."""
    lo, hi = base
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size:
        while v.min() < lo:
            lo -= step
        while v.max() > hi:
            hi += step
    return lo, hi


def power_unit(peak: float) -> tuple[float, str]:
    """(factor, unit) that show a power of ``peak`` [W] as a number of at least 1: W on
    the paper's bench, nW on a link tens of metres long."""
    for factor, unit in ((1.0, "W"), (1e3, "mW"), (1e6, "uW"), (1e9, "nW")):
        if peak * factor >= 1.0:
            return factor, unit
    return 1e12, "pW"


class Overlay:
    """Panel with the time and scrolling traces of phi and of P1, P2 (a pan-tilt head's
    azimuth and elevation, and its data detector's and one pointing photodiode's powers).

    Args:
        width, height: frame size [px].
        seconds_shown: history of the traces [s].
        sample_period: time between two :meth:`push` calls [s] (the control period).
        label: text beside the time.
        estimate: draw an estimate of phi beside the true one.
    """

    def __init__(self, width: int, height: int, seconds_shown: float = 5.0,
                 sample_period: float = 0.01, label: str = "", estimate: bool = True):
        self.w, self.h = width, height
        self.panel_h = max(90, int(0.3 * height))
        self.seconds = seconds_shown
        self.n = max(2, int(round(seconds_shown / sample_period)) + 1)
        self.phi, self.phihat, self.p1, self.p2 = (deque(maxlen=self.n) for _ in range(4))
        # a pan-tilt head's elevation, true and estimated (empty on one axis)
        self.elevation, self.elevation_hat = deque(maxlen=self.n), deque(maxlen=self.n)
        #: the two powers' names (a quad's: its data detector and a pointing photodiode)
        self.names = ("P1", "P2")
        self.label = label
        self.estimate = estimate
        size = self.font_px = max(10, height // 40)
        try:
            self.font = ImageFont.load_default(size=size)
        except TypeError:  # Pillow < 10.1 has only the fixed bitmap font
            self.font = ImageFont.load_default()

    status = ""
    vehicle = ""  # a line on the vehicle (IMU, hull offset, thrust) under the time

    def push(self, phi: float, phihat: float, p1: float, p2: float,
             elevation: float | None = None, elevation_hat: float | None = None) -> None:
        """One step: phi (a pan-tilt's azimuth) true and estimated [rad], two powers
        [W], and on a pan-tilt head its elevation true and estimated [rad]."""
        for q, v in ((self.phi, phi), (self.phihat, phihat), (self.p1, p1), (self.p2, p2)):
            q.append(v)
        if elevation is not None:
            self.elevation.append(elevation)
            self.elevation_hat.append(np.nan if elevation_hat is None else elevation_hat)

    def draw(self, frame: np.ndarray, t: float, peak_power: float) -> np.ndarray:
        y0 = self.h - self.panel_h
        frame[y0:] = (frame[y0:] * 0.3).astype(np.uint8)  # darken the panel area
        img = Image.fromarray(frame)
        d = ImageDraw.Draw(img)
        half = self.w // 2
        bottom = self.h - 8 - self.font_px  # room for the time axis labels
        boxes = [(8 + 4 * self.font_px, y0 + 22, half - 8, bottom),
                 (half + 8 + 4 * self.font_px, y0 + 22, self.w - 8, bottom)]
        # Scaled to the true angle: an estimate not yet handed over (a minimum-time
        # acquisition's first 0.2 s) swings by radians and flattened the rest; it is
        # clipped at the panel's edge instead.
        lim_phi = axis_limits(np.asarray(list(self.phi) + list(self.elevation)), (-0.5, 0.5),
                              0.5)
        lim_p = axis_limits(np.concatenate([list(self.p1), list(self.p2)]),
                            (-0.1 * peak_power, 1.1 * peak_power), 0.5 * peak_power)
        self._axes(d, boxes[0], lim_phi, "{:+.1f}", zero=True)
        scale, unit = power_unit(peak_power)
        self._axes(d, boxes[1], lim_p, "{:.1f}", zero=False, scale=scale)
        self._trace(d, boxes[0], self.phi, lim_phi, TRUE)
        if self.estimate:
            self._trace(d, boxes[0], self.phihat, lim_phi, ESTIMATE)
        if self.elevation:
            self._trace(d, boxes[0], self.elevation, lim_phi, ELEVATION)
            if self.estimate:
                self._trace(d, boxes[0], self.elevation_hat, lim_phi, ELEVATION_ESTIMATE)
            legend = "azimuth (white), elevation (green) [rad]" + (
                "; estimates (blue, pink)" if self.estimate else "")
        else:
            legend = "phi [rad]: true (white)" + (", estimate (blue)" if self.estimate
                                                  else "")
        self._trace(d, boxes[1], self.p1, lim_p, ESTIMATE)
        self._trace(d, boxes[1], self.p2, lim_p, P2)
        d.text((8, y0 + 4), legend, fill=TEXT, font=self.font)
        first, second = self.names
        d.text((half + 8, y0 + 4), f"power [{unit}]: {first} (blue), {second} (orange)",
               fill=TEXT, font=self.font)
        d.text((8, 6), f"t = {t:5.2f} s   {self.label}", fill=(255, 255, 255), font=self.font)
        if self.vehicle:
            d.text((8, 10 + self.font_px), self.vehicle, fill=TEXT, font=self.font)
        if self.status in STATUS_BADGES:
            text, colour = STATUS_BADGES[self.status]
            x0 = self.w - 8 - d.textlength(text, font=self.font) - 12
            d.rectangle((x0, 4, self.w - 8, 10 + self.font_px + 6), fill=colour)
            d.text((x0 + 6, 8), text, fill=(0, 0, 0), font=self.font)
        return np.asarray(img)

    def _axes(self, d, box, limits, fmt: str, zero: bool, scale: float = 1.0) -> None:
        """Frame, a tick at each end of the value axis, a zero line, and a time axis with
        a tick per second (0 s is now, at the right)."""
        x0, y0, x1, y1 = box
        lo, hi = limits
        d.rectangle(box, outline=(90, 110, 120))
        for value, y in ((hi, y0), (lo, y1)):
            d.text((x0 - 4 * self.font_px, y - self.font_px // 2), fmt.format(value * scale),
                   fill=TEXT, font=self.font)
        if zero and lo < 0 < hi:
            y = y1 - (0 - lo) / (hi - lo) * (y1 - y0)
            d.line([(x0, y), (x1, y)], fill=GRID, width=1)
        for k in range(int(self.seconds) + 1):
            x = x1 - k * (x1 - x0) / self.seconds
            d.line([(x, y1), (x, y1 + 3)], fill=TEXT, width=1)
            text = "0 s" if k == 0 else f"-{k}"
            d.text((x - d.textlength(text, font=self.font) / 2, y1 + 3), text, fill=TEXT,
                   font=self.font)

    def _trace(self, d, box, values, limits, colour) -> None:
        if len(values) < 2:
            return
        x0, y0, x1, y1 = box
        lo, hi = limits
        v = np.clip((np.asarray(values) - lo) / (hi - lo), 0.0, 1.0)
        xs = x1 - (len(v) - 1 - np.arange(len(v))) * (x1 - x0) / (self.n - 1)
        ys = y1 - v * (y1 - y0)
        d.line(list(zip(xs.tolist(), ys.tolist(), strict=True)), fill=colour, width=2)
