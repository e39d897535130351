"""A diaphragm's restoring stiffness: a linear hinge spring on the first mode with its
length held at the free-surface prediction (spring and length trade against each other:
with the length free within 1 % of the prediction a record whose length was 2 % off it
left the stiffness at 0.12 +/- 0.71 N m/rad, not distinguishable from zero), proposed when
the case says there is a diaphragm or the fitted frequency is off the prediction."""

from __future__ import annotations

import math
from collections.abc import Sequence

from analogs import HingeSpring, Pendulum

from ...fitting.result import FitResult
from ..scoring import distinct
from .base import Context, Family, Proposal, Score, frequency
from .hinge import HOST

__all__ = ["DiaphragmStiffness", "FREQUENCY_OFF"]

#: A first-mode frequency this far off the free-surface prediction (relative) makes the
#: diaphragm's hinge spring a candidate even when the case file mentions no diaphragm.
FREQUENCY_OFF = 0.03
#: A frequency trend with the swing amplitude of this many standard errors is an amplitude
#: law, not a linear spring's constant offset.
TREND_T = 3.0


class DiaphragmStiffness(Family):
    """A restoring stiffness the liquid alone lacks (a diaphragm): a hinge spring on the
    first mode with its length held at the prediction, when the case says there is a
    diaphragm or the fitted frequency is off the prediction."""

    cause = "diaphragm_stiffness"

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        model, current, ev = ctx.model, ctx.current, ctx.evidence
        ratio = ev.frequency_ratio
        off = ratio is not None and abs(ratio - 1) > FREQUENCY_OFF
        diaphragm = current.problem.experiments[0].case.tank.diaphragm
        names = {(type(c), c.name) for c in model.components}
        if (Pendulum, HOST) not in names or (HingeSpring, HOST) in names \
                or f"{HOST}.length" not in ctx.predicted or not (off or diaphragm):
            return []
        Lp = ctx.predicted[f"{HOST}.length"]
        m = current.value(f"{HOST}.mass")
        f1 = frequency(current, HOST)
        w2 = (2 * math.pi * f1) ** 2 if math.isfinite(f1) else ctx.gravity / Lp
        k0 = max(m * Lp**2 * w2 - m * ctx.gravity * Lp, 0.05 * m * ctx.gravity * Lp)
        pinned = f"; `{HOST}.length` was pinned at its bound" if f"{HOST}.length" in ev.pinned else ""

        def plausible(r: FitResult) -> str | None:
            if not distinct(r, f"{HOST}.stiffness"):
                return "the hinge stiffness is not distinguishable from zero"
            return None

        def describe(r: FitResult) -> str:
            k = r.value(f"{HOST}.stiffness")
            if not ratio:
                return f"a hinge spring on {HOST} (k = {k:.3g} N m/rad)"
            raise_ = math.sqrt(1 + k / (r.value(f"{HOST}.mass") * ctx.gravity
                                        * r.value(f"{HOST}.length"))) - 1
            zeta = r.derived.get(f"{HOST}.damping_ratio", (math.nan, 0))[0]
            return (f"the fitted frequency is {100 * (ratio - 1):+.1f} % off the free-surface "
                    f"prediction{pinned} -> a restoring stiffness the liquid alone lacks "
                    f"(diaphragm); a hinge spring on {HOST} with the length held at the "
                    f"prediction (k = {k:.3g} N m/rad, +{100 * raise_:.1f} % frequency, damping "
                    f"ratio {zeta:.3g})")

        # a frequency off the prediction that does not move with the swing is a linear
        # spring's: fitted first (when it reaches the noise, nothing else needs a fit); a
        # frequency that moves with the swing (a hardening hinge) is fitted after the
        # screened families (cubic_b: a linear spring fitted first removed most of a
        # hardening hinge's residual and its 5x gain left the cubic spring unfitted)
        trend = ev.frequency_trend
        amplitude_law = trend is not None and abs(trend.t) >= TREND_T
        return [Proposal(self.cause, (f"{HOST}:spring",), model + HingeSpring(HOST),
                         ctx.measurement, {f"{HOST}.stiffness": k0, f"{HOST}.length": Lp},
                         hold={f"{HOST}.length": Lp}, cold_start={f"{HOST}.stiffness": k0},
                         first=not amplitude_law,
                         plausible=plausible, describe=describe)]
