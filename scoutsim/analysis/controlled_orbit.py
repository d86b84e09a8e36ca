"""The periodic orbit of the controlled robot: the fixed point of the sampled stride map
(:func:`~scoutsim.analysis.stride_map.controlled_stride_map`) by Newton's method, and its
Floquet multipliers (docs/orbits.md).

Newton's method with the stride map's Jacobian carried with the run (or by forward
differences) and least-squares steps (pinned legs and stuck motor joints make some
coordinates dependent) converges to a residual ~1e-12; the eigenvalues of the Jacobian at
the fixed point are the multipliers. On the Scout II
defaults (Model II, default floor) the orbit lasts 234 ms with spectral radius 0.925.

Units: SI (section coordinates as :data:`~scoutsim.analysis.stride_map.CONTROLLED_Z_NAMES`,
period [s], speed [m/s], angles [rad]; degrees only in ``to_dict``).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..names import LEG_NAMES
from ..parameters import DEFAULT_FRICTION_COEFFICIENT
from ..simulation.integrator import IntegratorSettings
from ..simulation.simulator import simulate
from ..state import HybridState
from .poincare import MapError, floquet_multipliers
from .stride_map import (
    CONTROLLED_Z_NAMES,
    SECTION_LABELS,
    Crossing,
    StrideMap,
    mode_signature,
    section_state,
)

__all__ = [
    "ControlledOrbit",
    "NewtonSettings",
    "cell_change",
    "controlled_fixed_point",
    "difference_jacobian",
    "stride_jacobian",
    "JACOBIAN_METHODS",
    "likely_strides",
    "map_noise",
    "newton_step",
    "NewtonError",
    "NOISE_MULTIPLE",
]


#: how a stride map's Jacobian can be obtained (NewtonSettings.jacobian)
JACOBIAN_METHODS = ("exact", "fd")
#: a Newton that stops above its tolerance is accepted if its residual is within this many
#: times the map's rounding noise there (:func:`map_noise`)
NOISE_MULTIPLE = 10.0
#: perturbations probed by :func:`map_noise`, and their size relative to max(1, |z_j|)
NOISE_PROBES = 3
NOISE_STEP = 1e-12


class NewtonError(MapError):
    """Newton found no fixed point: ``residual`` is the smallest max|P(z) - z| it reached
    (SI units of each coordinate), ``noise`` the map's rounding noise measured there."""

    def __init__(self, message: str, residual: float, noise: float = math.nan):
        super().__init__(message)
        self.residual = residual
        self.noise = noise


@dataclass(frozen=True)
class NewtonSettings:
    """How :func:`controlled_fixed_point` runs Newton's method.

    tol : target residual max|P(z) - z| (SI units of each coordinate). Where Newton stops
        above it (no step reduces the residual, or ``max_iter`` reached), the map's own
        rounding noise at that point is measured (:func:`map_noise`) and the orbit accepted
        if the residual is within ``NOISE_MULTIPLE`` times it: a cycle of many strides
        integrated for seconds carries more rounding than ``tol`` (the residual and the
        noise are reported).
    max_iter : Newton iterations at most.
    jacobian_step : relative step of the difference Jacobian (times max(1, |z_j|)).
    jacobian : how dP/dz is obtained: "exact" (carried with the run, internal
        differentiation: :mod:`scoutsim._core.numerics.tangent`; for a controller the
        compiled loop runs, the built-in Table I law or a CompiledController), "fd"
        (forward differences of whole strides), or None: "exact" where it can be, else
        "fd" (a Python controller).
    """

    tol: float = 1e-10
    max_iter: int = 10
    jacobian_step: float = 1e-6
    jacobian: str | None = None

    def __post_init__(self):
        if self.jacobian not in JACOBIAN_METHODS + (None,):
            raise ValueError(
                f"jacobian = {self.jacobian!r}: must be one of {list(JACOBIAN_METHODS)} or None"
            )


@dataclass
class ControlledOrbit:
    """Fixed point of the controlled stride map (section: the first control sample after
    the back leg's lift-off, :class:`~scoutsim.analysis.stride_map.StrideMap`)."""

    z: np.ndarray  # section coordinates (CONTROLLED_Z_NAMES), SI
    state: object  # the HybridState at the section
    period: float  # [s], a whole number of control periods
    residual: float  # max |P(z) - z| (SI units of each coordinate)
    multipliers: np.ndarray  # eigenvalues of dP/dz (complex)
    jacobian: np.ndarray = field(repr=False)
    iterations: int = 0
    history: list = field(default_factory=list)  # residual per Newton iteration
    #: leg angle from the world vertical (theta + phi) at each leg's touchdown on the orbit
    #: [rad] (back, front; linear interpolation between the 1 kHz samples)
    touchdown_angles_world: tuple = (math.nan, math.nan)
    mean_speed: float = math.nan  # forward travel over the period / period [m/s]
    #: names of the section coordinates z (StrideMap.z_names)
    z_names: tuple = CONTROLLED_Z_NAMES
    #: distance of the lift-off on the orbit from the nearer sample boundary [s]: a
    #: parameter change that moves it by more moves the section by a sample
    section_margin: float = math.nan
    #: strides per period (the orbit is a fixed point of the stride map's strides-th iterate)
    strides: int = 1
    #: what the section is (StrideMap.section_label)
    section_label: str = SECTION_LABELS["plant"]
    #: how it was found: model, friction_coefficient, robot, controller, integrator and
    #: section (what orbit_sensitivity needs to perturb it)
    setting: dict = field(default_factory=dict, repr=False)
    #: how ``jacobian`` was obtained: "exact" (carried with the run) or "fd" (differences:
    #: asked for, or where the carried one does not exist, :func:`stride_jacobian`)
    jacobian_method: str = "fd"
    #: the map's rounding noise at the orbit (:func:`map_noise`, SI units of each
    #: coordinate), measured where Newton stopped above its tolerance and the orbit was
    #: accepted within NOISE_MULTIPLE times it; NaN where Newton met its tolerance
    residual_noise: float = math.nan

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    def to_dict(self) -> dict:
        return {
            "section": self.section_label,
            "section_margin_s": self.section_margin,
            "jacobian_method": self.jacobian_method,
            "strides_per_period": self.strides,
            "touchdown_angle_back_deg": math.degrees(self.touchdown_angles_world[0]),
            "touchdown_angle_front_deg": math.degrees(self.touchdown_angles_world[1]),
            "state": {n: float(v) for n, v in zip(self.z_names, self.z)},
            "period_s": self.period,
            "mean_speed_m_s": self.mean_speed,
            "residual": self.residual,
            "residual_noise": self.residual_noise,
            "eigenvalues": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "spectral_radius": float(np.max(np.abs(self.multipliers))),
            "stable": self.stable,
            "iterations": self.iterations,
            "residual_history": [float(v) for v in self.history],
        }


def controlled_fixed_point(
    start=None,
    *,
    model: str = "II",
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    robot=None,
    controller=None,
    integrator: IntegratorSettings | None = None,
    settle_duration: float = 12.0,
    newton: NewtonSettings | None = None,
    progress=None,
    strides: int | None = None,
    section: str | None = None,
) -> ControlledOrbit:
    """Periodic orbit of the controlled robot by Newton's method on the sampled stride map
    (:class:`~scoutsim.analysis.stride_map.StrideMap`: section at the first control sample
    after the back leg's lift-off), and its Floquet multipliers, for any controller whose
    state scoutsim can read and set (the built-in Table I law, a
    :class:`~scoutsim.control.compiled.CompiledController`, a Python controller with
    ``get_state()`` / ``set_state(values)``).

    The closed loop is a sampled-data system: between samples the plant flows, at samples
    the controller switches. The stride map is smooth as long as the lift-off and every
    controller switch stay on the same sample, so a fixed point is a periodic orbit of a
    whole number of control periods, and Newton converges on it quadratically (within a
    sample-phase cell).

    ``start``: None (a ``settle_duration`` [s] run from the default start, at the default
    integrator, then to the next section sample), a :class:`~scoutsim.SimulationResult` of
    a steady bound (its second-to-last back-leg lift-off; a controller that keeps its own
    state or reads its held torques is settled three more strides from there, since a
    result records neither), or a HybridState at a section sample (as
    :attr:`ControlledOrbit.state`). ``newton``: :class:`NewtonSettings` (the target
    residual ``tol``, ``max_iter``, the Jacobian's method ``jacobian`` and
    ``jacobian_step``). Jacobian: "exact", carried with the run through its steps, events
    and samples (the default for the built-in law and a CompiledController;
    :func:`stride_jacobian`), or "fd", forward differences with steps ``jacobian_step``
    max(1, |z_j|) (backward where the forward step moves the section or a controller
    switch by a sample: the map's jump, not its derivative). Newton steps by
    least squares (the dependent coordinates of pinned legs and stuck motor joints make
    ``dP/dz - I`` rank deficient), globalised by halving a step that does not reduce the
    residual (or makes the robot fall) up to five times. Default integrator: DOPRI5 at
    rtol 1e-11 / atol 1e-12, so the map is accurate well below ``tol``. MapError, saying
    why, if the discrete modes at the section change, Newton stalls or no fixed point is
    found within ``max_iter`` iterations; a Python controller that raises in a stride
    stops the search with its ControllerError. ``progress``: optional callable(str), told the
    settling run and each Newton iteration's residual.

    ``strides``: strides per period of the orbit, the fixed point of the map's
    ``strides``-th iterate (None: the cycle the map settles on, read from 48 strides after
    32 more at the orbit's integrator (up to 240 if they do not repeat),
    :func:`likely_strides`; Newton from their end for the three most likely
    numbers of strides in turn, and a fixed point of the k-th iterate that is one of a
    shorter period reported with that period). A sampled controller can lock into a cycle of
    several strides of different whole numbers of control periods, and such a cycle can
    coexist with a period-1 orbit (Model I under the Table I law: docs/orbits.md); the
    orbit found is the one the start is on. ``section``: "plant" or "controller" (:class:`StrideMap`; default: the
    built-in law's own lift-off detection for that law, the plant's lift-off otherwise)."""
    integ = integrator or IntegratorSettings(rtol=1e-11, atol=1e-12)
    ns = newton or NewtonSettings()
    tol, max_iter = ns.tol, ns.max_iter
    common = dict(
        model=model, friction_coefficient=friction_coefficient, robot=robot, controller=controller
    )
    m = StrideMap(integrator=integ, section=section, **common)
    method = ns.jacobian or ("exact" if m.compiled else "fd")
    if method == "exact" and not m.compiled:
        raise ValueError(
            "jacobian = 'exact' needs a controller the compiled loop runs (the built-in "
            "Table I law or a CompiledController); a Python controller's orbit takes "
            "jacobian = 'fd'"
        )
    how = (method, ns.jacobian_step)
    say = progress or (lambda message: None)
    if start is None:
        say(f"settling: {settle_duration:g} s of model {model} to a Newton start")
        start = (
            StrideMap(section=m.section, **common).crossing(None, settle_s=settle_duration).state
        )
    elif not isinstance(start, HybridState):
        start = section_state(start, m.section)
        if not m.builtin:
            say("settling: three strides from the run's last strides to a Newton start")
            settle = StrideMap(section=m.section, **common)
            for _ in range(3):
                start = settle.crossing(start).state
    if strides is not None:
        return _newton(m, start, strides, tol, max_iter, how, say, common, integ)
    ks, lengths, start, recurrence = likely_strides(m, start)
    say(
        f"settled stride lengths (control periods) {lengths[:12]}...: trying "
        f"{', '.join(map(str, ks))} stride(s) per period"
    )
    failures = []
    reached = math.inf
    for k in ks:
        try:
            orbit = _newton(m, start, k, tol, max_iter, how, say, common, integ)
        except MapError as exc:
            failures.append(f"{k} stride(s): {exc}")
            if isinstance(exc, NewtonError):
                reached = min(reached, exc.residual)
            continue
        for d in (d for d in range(1, k) if k % d == 0):
            # the fixed point of the k-th iterate may be one of a shorter period
            c = m.crossing(orbit.state, strides=d)
            if float(np.max(np.abs(m.z_of(c.state) - orbit.z))) < 100.0 * tol:
                say(f"the fixed point of {k} strides is one of {d}: Newton for {d} from it")
                return _newton(m, orbit.state, d, tol, max_iter, how, say, common, integ)
        return orbit
    closest = min(recurrence, key=lambda k: (recurrence[k], k))
    d = recurrence[closest]
    if min(d, reached) <= _REPEATS * tol:
        verdict = (
            "the gait repeats, but Newton did not reach its tolerance "
            f"(smallest residual {min(reached, d):.2g})"
        )
    else:
        verdict = (
            f"the gait does not repeat within {MAX_STRIDES_PER_PERIOD} strides "
            "(quasi-periodic, or still settling)"
        )
    raise MapError(
        "no periodic orbit from this start (settled stride lengths in control periods "
        f"{lengths}; the section states come closest to repeating every {closest} "
        f"stride(s), within {d:.2g} (max |z_(i+k) - z_i| over {_COMPARED} strides): "
        f"{verdict}): " + "; ".join(failures)
    )


def newton_step(J: np.ndarray, F: np.ndarray) -> np.ndarray:
    """The Newton step dz for the fixed point of a map P at z: (J - I) dz = -F, with J
    the map's Jacobian at z and F = P(z) - z; least squares (rcond 1e-12), so a map with
    a multiplier at 1 (a direction the section does not fix) gets the smallest step."""
    return np.linalg.lstsq(J - np.eye(F.size), -F, rcond=1e-12)[0]


def _newton(m, start, strides, tol, max_iter, how, say, common, integ):
    """Newton on the ``strides``-th iterate of the map ``m`` from ``start`` (see
    :func:`controlled_fixed_point`)."""
    disc = mode_signature(start)
    c = m.crossing(start, strides=strides)
    assert c.start is not None, "a crossing from a HybridState keeps its start"
    z, z1 = m.z_of(c.start), m.z_of(c.state)
    like = c.start
    hist: list[float] = []
    J = None
    used = how[0]
    it = 0
    stalled = ""
    for it in range(max_iter + 1):
        _same_modes(disc, c.state)
        F = z1 - z
        res = float(np.max(np.abs(F)))
        hist.append(res)
        say(f"Newton iteration {it}: residual max|P(z)-z| = {res:.2e}")
        if res < tol or it == max_iter:
            break
        J, used = stride_jacobian(m, z, like, c, how, strides)
        dz = newton_step(J, F)
        try:
            z, z1, c = _globalised_step(m, z, dz, like, res, disc, hist, strides)
        except NewtonError as exc:
            stalled = str(exc)
            break
    if J is None or (it > 0 and not stalled):
        J, used = stride_jacobian(m, z, like, c, how, strides)
    noise = math.nan
    if hist[-1] >= tol:
        noise = map_noise(m, z, like, c, J, strides)
        why = stalled or (
            f"Newton did not converge: residual {hist[-1]:.2e} after {it} iterations "
            f"(history {[f'{v:.1e}' for v in hist]})"
        )
        if not hist[-1] <= NOISE_MULTIPLE * noise:
            raise NewtonError(
                f"{why}; the map's own rounding noise here is {noise:.1e}",
                min(hist),
                noise,
            )
        say(
            f"Newton stopped at residual {hist[-1]:.2e} above its tolerance {tol:.0e}, "
            f"within {NOISE_MULTIPLE:g} x the map's own rounding noise there "
            f"({noise:.1e}): the orbit is found as closely as the map can tell"
        )
    hs = m.hs_of(z, like)
    T = c.period_s
    r = simulate(
        common["robot"],
        common["controller"],
        hs,
        T,
        model=common["model"],
        integrator=integ,
        friction_coefficient=common["friction_coefficient"],
    )
    td = []
    for leg in LEG_NAMES:
        te = r.event_times("touchdown", leg)
        if len(te) == 0:
            td.append(math.nan)
            continue
        g = r.pitch + r.leg_angle(leg)
        td.append(float(np.interp(te[0], r.t, g)))
    return ControlledOrbit(
        z=z,
        state=hs,
        period=T,
        residual=hist[-1],
        multipliers=floquet_multipliers(J),
        jacobian=J,
        iterations=len(hist) - 1,
        history=hist,
        touchdown_angles_world=tuple(td),
        mean_speed=float((r.x[-1] - r.x[0]) / (r.t[-1] - r.t[0])),
        z_names=m.z_names(hs),
        section_margin=c.margin_s,
        strides=strides,
        section_label=m.section_label,
        setting=dict(common, integrator=integ, section=m.section),
        jacobian_method=used,
        residual_noise=noise,
    )


#: strides per period searched for a repeating cycle; strides settled first, and compared;
#: cycles tried
MAX_STRIDES_PER_PERIOD = 16
_SETTLED = 2 * MAX_STRIDES_PER_PERIOD
_COMPARED = 3 * MAX_STRIDES_PER_PERIOD
#: section states that repeat within this many times Newton's tolerance count as a
#: cycle in the report of an orbit not found
_REPEATS = 1e4
_TRIED = 3
_ROUNDS = 3


def likely_strides(m: StrideMap, start: HybridState):
    """The strides per period of the cycle the map ``m`` settles on from the section
    state ``start``, most likely first: after 32 strides more, over the next 48, the k (up
    to 16) whose stride lengths in control periods repeat every k strides (tried again
    after 80 strides more, twice, while none do; then all k), ordered by how closely the
    section states repeat every k strides (d_k = max |z_(i+k) - z_i|): those within 30 x
    the smallest d_k first, shortest first (a bound still converging with an alternating
    multiplier lambda has d_1 / d_2 about 2 / (1 - lambda^2): 14 at lambda = -0.925). A
    sampled controller can lock into a cycle of strides of different whole numbers of
    control periods, and a gait can repeat only every other stride (a period doubling)
    with strides of equal length. Returns (the three most likely k, the last 48 stride
    lengths, the section state after them, {k: d_k})."""
    hs = start
    ks = range(1, MAX_STRIDES_PER_PERIOD + 1)
    for _ in range(_ROUNDS):
        ns, zs = [], []
        for i in range(_SETTLED + _COMPARED):
            c = m.crossing(hs)
            hs = c.state
            if i >= _SETTLED:
                ns.append(c.samples)
                zs.append(m.z_of(hs))
        repeating = [k for k in ks if all(ns[i + k] == ns[i] for i in range(len(ns) - k))]
        if repeating:
            break
    Z = np.array(zs)
    d = {k: float(np.max(np.abs(Z[k:] - Z[:-k]))) for k in (repeating or list(ks))}
    best = min(d.values())
    order = sorted(d, key=lambda k: (d[k] > 30.0 * best, k))
    return order[:_TRIED], ns, hs, d


def _same_modes(disc: dict, hs: HybridState) -> None:
    """MapError unless the discrete modes of ``hs`` are ``disc``."""
    if mode_signature(hs) != disc:
        raise MapError(
            f"the discrete state at the section changed ({disc} -> "
            f"{mode_signature(hs)}): not a period-1 orbit of this section"
        )


def cell_change(base: Crossing, c: Crossing) -> str:
    """How the stride ``c`` leaves the sample-phase cell and mode sequence of ``base``
    ("" if it does not): another number of control periods, the controller switching on
    other samples, or another sequence of plant events (one that appears or disappears:
    the orbit grazes it)."""
    if c.samples != base.samples:
        return f"the stride lasts {c.samples} control periods instead of {base.samples}"
    if not np.array_equal(c.leg_states, base.leg_states):
        return "a controller switch moves to another sample"
    if c.plant_events != base.plant_events:
        a, b = Counter(base.plant_events), Counter(c.plant_events)
        gone = [f"{k} ({LEG_NAMES[g]})" for (k, g) in (a - b)]
        new = [f"{k} ({LEG_NAMES[g]})" for (k, g) in (b - a)]
        parts = ([f"{', '.join(new)} appears"] if new else []) + (
            [f"{', '.join(gone)} disappears"] if gone else []
        )
        what = "; ".join(parts) or "reordered"
        return f"the plant's event sequence changes ({what}): the orbit grazes it"
    return ""


def stride_jacobian(
    m: StrideMap, z, like, base: Crossing, how, strides: int
) -> tuple[np.ndarray, str]:
    """dP/dz at ``z`` (whose stride is ``base``) by ``how`` = (method, step), and the method
    that gave it: "exact", carried with one more run of the stride, or "fd"
    (:func:`difference_jacobian` with the relative step). Where the carried Jacobian does
    not exist (a reset on the stride decided by a margin below the difference step: a
    perturbed copy took another branch; or the run carrying it left the stride's cell),
    the differences of whole strides are taken instead, and the method says so."""
    method, step = how
    if method == "exact":
        c = m.crossing(m.hs_of(z, like), strides=strides, exact=True)
        assert c.jacobian is not None and c.smoothness is not None, "an exact crossing has both"
        if not cell_change(base, c) and not c.smoothness["nonsmooth"]:
            return c.jacobian, "exact"
    return difference_jacobian(m, z, like, base, step, strides), "fd"


def difference_jacobian(
    m: StrideMap, z, like, base: Crossing, step: float, strides: int
) -> np.ndarray:
    """dP/dz at ``z`` (whose stride is ``base``) by forward differences, a column by
    backward differences where the forward step leaves the sample-phase cell or the mode
    sequence; MapError, saying how, if both do (the map is not smooth here)."""
    z1 = m.z_of(base.state)
    J = np.empty((z.size, z.size))
    names = m.z_names(like)
    for j in range(z.size):
        e = step * max(1.0, abs(z[j]))
        why = ""
        for sign in (1.0, -1.0):
            zp = z.copy()
            zp[j] += sign * e
            cj = m.crossing(m.hs_of(zp, like), strides=strides)
            why = cell_change(base, cj)
            if not why:
                J[:, j] = (m.z_of(cj.state) - z1) / (sign * e)
                break
        else:
            raise MapError(
                f"the stride map is not smooth here: under a perturbation of {names[j]} by "
                f"+-{e:.1e} {why} (the lift-off lies {base.margin_s * 1e6:.2f} us from a "
                "sample boundary)"
            )
    return J


def _globalised_step(m: StrideMap, z, dz, like, res: float, disc: dict, hist: list, strides: int):
    """The Newton step ``dz`` from ``z``, halved until it reduces the residual
    max|P(z) - z| below ``res`` (at most five halvings): (z, P(z), its crossing)."""
    why = ""
    lam = 1.0
    for _ in range(6):
        try:
            c = m.crossing(m.hs_of(z + lam * dz, like), strides=strides)
            if mode_signature(c.state) != disc:
                raise MapError("the discrete state at the section changed")
            assert c.start is not None, "a crossing from a HybridState keeps its start"
            zt, zt1 = m.z_of(c.start), m.z_of(c.state)
            rt = float(np.max(np.abs(zt1 - zt)))
            if rt < res:
                return zt, zt1, c
            why = f"residual {rt:.2e}"
        except MapError as exc:
            why = str(exc)
        lam *= 0.5
    raise NewtonError(
        f"Newton stalled: no step along the Newton direction (down to 1/32 of it) reduces "
        f"the residual {res:.2e} (the last: {why}; history "
        f"{[f'{v:.1e}' for v in hist]})",
        min(hist),
    )


def map_noise(m: StrideMap, z, like, base: Crossing, J, strides: int) -> float:
    """The rounding noise of the residual F(z) = P(z) - z at ``z`` (whose stride is
    ``base``, Jacobian ``J``): the largest |F(z + d) - F(z) - (J - I) d| over NOISE_PROBES
    perturbations d of NOISE_STEP max(1, |z_j|) with fixed sign patterns (so the
    measurement is deterministic). The linear part is removed, so what is left is what the
    integration's rounding over the ``strides`` strides does to the map; a perturbation
    that leaves the stride's cell is not counted. NaN if none stays in it."""
    assert base.start is not None, "a crossing from a HybridState keeps its start"
    z0 = m.z_of(base.start)
    F0 = m.z_of(base.state) - z0
    # Walsh-like sign patterns: alternating by 1, 2, 4, ... coordinates
    j = np.arange(z.size)
    signs = [np.where((j >> k) & 1, -1.0, 1.0) for k in range(NOISE_PROBES)]
    A = J - np.eye(z.size)
    worst = math.nan
    for s in signs:
        d = s * NOISE_STEP * np.maximum(1.0, np.abs(z))
        try:
            c = m.crossing(m.hs_of(z + d, like), strides=strides)
        except MapError:
            continue
        if cell_change(base, c):
            continue
        assert c.start is not None, "a crossing from a HybridState keeps its start"
        zp = m.z_of(c.start)
        e = float(np.max(np.abs(m.z_of(c.state) - zp - F0 - A @ (zp - z0))))
        worst = e if math.isnan(worst) else max(worst, e)
    return worst
