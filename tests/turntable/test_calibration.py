"""Orientation error → multiposition calibration error (seed 001, eqs. 7–16), checked against the
equations written out literally, hand-derived first-order deviations, an independent brute-force
implementation (turntable kinematics by scipy's Rotation, one np.linalg.lstsq per grid point) and
the paper's qualitative conclusions (1)–(3) of §2.2."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
    coefficient_names,
    earth_rate_and_gravity,
    multiposition_plan,
)
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG, TABLE1_COEFFICIENTS
from rotacal.turntable.calibration import (
    COMPONENTS,
    METHODS,
    OrientationRequirement,
    actual_inputs,
    coefficient_deviation,
    orientation_matrix,
    orientation_requirement,
    rate_error_surfaces,
    rate_error_vectors,
    rate_sensing_error,
    rate_sensing_error_from_rotation,
)

ARCMIN = math.radians(1.0 / 60.0)


# ------------------------------------------------------------------- independent brute force


def _literal_eq7(p: float, t: float, g: float) -> np.ndarray:
    return np.array([[1.0, -t, p], [t, 1.0, -g], [-p, g, 1.0]])


def _columns(a: np.ndarray, axis: str) -> np.ndarray:
    ax, ay, az = a[:, 0], a[:, 1], a[:, 2]
    sq = ax * ax if axis == "x" else ay * ay
    return np.column_stack([np.ones_like(ax), ax, ay, az, sq, az * az, ax * ay])


class BruteForce:
    """The seed's eqs. (5)–(13) one orientation error at a time, with the turntable's kinematics
    from scipy (gyro frame = R_d⁻¹·world, R_d = Ry(φ1)·Rz(φ2), actual frame R_t = R_d·ΔR)."""

    def __init__(self, p1, p2, lat_deg, coefficients=None, method="coefficients"):
        self.rd = Rotation.from_euler("YZ", np.column_stack([p1, p2]), degrees=True).as_matrix()
        lam = math.radians(lat_deg)
        self.earth = EARTH_RATE_DEG_H * np.array([math.cos(lam), 0.0, math.sin(lam)])
        self.up = np.array([0.0, 0.0, 1.0])
        self.method = method
        coef = coefficients or {}
        self.beta = {
            ax: np.array(
                [{**TABLE1_COEFFICIENTS[ax], **coef.get(ax, {})}[k] for k in coefficient_names(ax)]
            )
            for ax in ("x", "y")
        }

    def inputs(self, delta_r):
        """ω, a in the frame R = R_d·ΔR (ΔR (3, 3) or (n, 3, 3))."""
        r = self.rd @ delta_r
        w = np.einsum("nji,j->ni", r, self.earth)  # Rᵀ·v
        a = np.einsum("nji,j->ni", r, self.up)
        return w, a

    def run(self, delta_r):
        w0, a0 = self.inputs(np.eye(3))
        w1, a1 = self.inputs(delta_r)
        out = {}
        for k, axis in enumerate(("x", "y")):
            a_nom, a_act = _columns(a0, axis), _columns(a1, axis)
            b2, b2p = w0[:, k], w1[:, k]
            b1 = b2p + a_act @ self.beta[axis]  # the physical outputs
            beta1 = np.linalg.lstsq(a_nom, b1 - b2, rcond=None)[0]  # eq. (6)
            beta2 = np.linalg.lstsq(a_act, b1 - b2p, rcond=None)[0]  # eq. (11)
            dbeta = beta1 - beta2  # eq. (12)
            if self.method == "coefficients":
                vec = a_nom @ dbeta
            elif self.method == "earth-rate":
                vec = b2p - b2  # the Earth-rate reading alone (eq. (16)'s)
            else:
                vec = b1 - a_nom @ beta2 - b2p  # eq. (13) as printed
            out[axis] = (dbeta, vec, beta2)
        return out


def _default_plan():
    plan = multiposition_plan()
    return plan.phi1_deg, plan.phi2_deg


# ------------------------------------------------------------------------------ eq. (7), (8)


def test_orientation_matrix_is_eq7_literally():
    rng = np.random.default_rng(1)
    p, t, g = rng.normal(0, 1e-3, (3, 4, 5))
    r = orientation_matrix(p, t, g)
    assert r.shape == (4, 5, 3, 3)
    for i in range(4):
        for j in range(5):
            np.testing.assert_array_equal(r[i, j], _literal_eq7(p[i, j], t[i, j], g[i, j]))
    # broadcasting and the contract's component order: ΔR[0,2] = Δψ, ΔR[1,0] = Δθ, ΔR[2,1] = Δγ
    r = orientation_matrix(0.1, np.array([0.2, 0.3]), 0.4)
    assert r.shape == (2, 3, 3)
    assert (r[1, 0, 2], r[1, 1, 0], r[1, 2, 1]) == (0.1, 0.3, 0.4)


@pytest.mark.parametrize("method", METHODS)
def test_zero_orientation_error_gives_zero_exactly(method):
    wx, wy = rate_sensing_error(0.0, 0.0, 0.0, method=method)
    assert wx == 0.0 and wy == 0.0
    p1, p2 = _default_plan()
    wx, wy = rate_sensing_error_from_rotation(
        np.broadcast_to(np.eye(3), (p1.size, 3, 3)), phi1_deg=p1, phi2_deg=p2, method=method
    )
    assert wx == 0.0 and wy == 0.0
    bx, by = coefficient_deviation(np.zeros(3), 0.0, 0.0)
    assert np.all(bx == 0.0) and np.all(by == 0.0)


def test_small_dtheta_changes_the_x_input_by_omega_y_dtheta():
    # eq. (8) row form: ωx' = ωx + ωy·Δθ − ωz·Δψ, ωy' = ωy − ωx·Δθ + ωz·Δγ, ωz' = ωz + ωx·Δψ − ωy·Δγ
    p1, p2 = _default_plan()
    lat = 30.0
    w, a = earth_rate_and_gravity(p1, p2, lat)
    dth = 2e-4
    w1, a1 = actual_inputs(0.0, dth, 0.0, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)
    np.testing.assert_allclose(w1[:, 0] - w[:, 0], w[:, 1] * dth, rtol=0, atol=1e-13)
    np.testing.assert_allclose(w1[:, 1] - w[:, 1], -w[:, 0] * dth, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(w1[:, 2], w[:, 2])
    np.testing.assert_allclose(a1[:, 0] - a[:, 0], a[:, 1] * dth, rtol=0, atol=1e-15)
    # and every component against the turntable kinematics (R_t = R_d·ΔR, scipy)
    bf = BruteForce(p1, p2, lat)
    e = (3e-4, -2e-4, 5e-4)
    w1, a1 = actual_inputs(*e, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)
    wb, ab = bf.inputs(_literal_eq7(*e))
    np.testing.assert_allclose(w1, wb, rtol=0, atol=1e-13)
    np.testing.assert_allclose(a1, ab, rtol=0, atol=1e-15)


@pytest.mark.parametrize("lat", [DEFAULT_LATITUDE_DEG, -20.0])
def test_first_order_coefficient_deviation_for_dtheta_by_hand(lat):
    # Δθ alone on the 45° grid: a' − a = (ay, −ax, 0)·Δθ, ω' − ω = (ωy, −ωx, 0)·Δθ. Using
    # ax² + ay² + az² = 1 and ωy = −Ωe·cosλ·sinφ2·cosφ1 + Ωe·sinλ·ay (the first term is orthogonal
    # to every column of A on this grid; likewise for ωx), eq. (12) gives to first order:
    x, y = TABLE1_COEFFICIENTS["x"], TABLE1_COEFFICIENTS["y"]
    ws = EARTH_RATE_DEG_H * math.sin(math.radians(lat))
    hand_x = [x["Dxy"], -x["Dy"], x["Dx"] + ws, 0.0, -2 * x["Dxy"], -x["Dxy"], 2 * x["Dxx"]]
    hand_y = [-y["Dyx"], -(y["Dy"] + ws), y["Dx"], 0.0, 2 * y["Dyx"], y["Dyx"], -2 * y["Dyy"]]
    h = 1e-5
    px, py = coefficient_deviation(0.0, h, 0.0, latitude_deg=lat)
    mx, my = coefficient_deviation(0.0, -h, 0.0, latitude_deg=lat)
    np.testing.assert_allclose((px - mx) / (2 * h), hand_x, rtol=0, atol=1e-9)
    np.testing.assert_allclose((py - my) / (2 * h), hand_y, rtol=0, atol=1e-9)
    # and Δω_vec = A·Δβ at first order
    p1, p2 = _default_plan()
    vx = rate_error_vectors(0.0, h, 0.0, latitude_deg=lat)[0]
    vx = (vx - rate_error_vectors(0.0, -h, 0.0, latitude_deg=lat)[0]) / (2 * h)
    bf = BruteForce(p1, p2, lat)
    a_nom = _columns(bf.inputs(np.eye(3))[1], "x")
    np.testing.assert_allclose(vx, a_nom @ np.array(hand_x), rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    ("plan", "lat", "coef"),
    [
        (None, DEFAULT_LATITUDE_DEG, None),
        ((12, 8, 10.0, 0.0), -33.9, {"x": {"Dz": 4.0, "Dzz": 1.5}, "y": {"DF": 0.0}}),
        ((6, 16, 0.0, 5.0), 80.0, None),
    ],
)
def test_vectorised_equals_brute_force_lstsq(method, plan, lat, coef):
    if plan is None:
        p1, p2 = _default_plan()
    else:
        pl = multiposition_plan(
            outer_steps=plan[0],
            inner_steps=plan[1],
            outer_offset_deg=plan[2],
            inner_offset_deg=plan[3],
        )
        p1, p2 = pl.phi1_deg, pl.phi2_deg
    g = np.linspace(-1e-3, 1e-3, 4)
    pp, tt, gg = np.meshgrid(g, g[::-1] * 0.7, g * 1.3, indexing="ij")
    kw = {"phi1_deg": p1, "phi2_deg": p2, "latitude_deg": lat, "coefficients": coef}
    wx, wy = rate_sensing_error(pp, tt, gg, method=method, **kw)
    bx, by = coefficient_deviation(pp, tt, gg, **kw)
    assert wx.shape == pp.shape and bx.shape == (*pp.shape, 7)
    bf = BruteForce(p1, p2, lat, coef, method)
    for idx in np.ndindex(pp.shape):
        ref = bf.run(_literal_eq7(pp[idx], tt[idx], gg[idx]))
        for axis, w, b in (("x", wx, bx), ("y", wy, by)):
            dbeta, vec, beta2 = ref[axis]
            np.testing.assert_allclose(beta2, bf.beta[axis], rtol=1e-12, atol=1e-12)  # eq. (11)
            assert w[idx] == pytest.approx(np.max(np.abs(vec)), abs=1e-12)
            np.testing.assert_allclose(b[idx], dbeta, rtol=0, atol=1e-11)


def test_per_position_rotation_against_brute_force_and_uniform_case():
    p1, p2 = _default_plan()
    n = p1.size
    rng = np.random.default_rng(7)
    e = rng.uniform(-5e-4, 5e-4, 3)
    # the same ΔR at every position equals rate_sensing_error, both methods
    r = np.broadcast_to(_literal_eq7(*e), (n, 3, 3))
    for method in METHODS:
        got = rate_sensing_error_from_rotation(r, phi1_deg=p1, phi2_deg=p2, method=method)
        ref = rate_sensing_error(*e, method=method)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-15)
    # a batch of ΔR that vary with φ2 (like eq. (26)), and proper rotations, vs the brute force
    phi2 = np.radians(p2)
    batch = []
    for k in range(3):
        a, b, c = rng.uniform(-4e-4, 4e-4, 3)
        dpsi = a * np.cos(phi2) - b * np.sin(phi2) + c
        dgam = a * np.sin(phi2) + b * np.cos(phi2)
        dth = np.full(n, c * (k - 1))
        batch.append(np.stack([_literal_eq7(*v) for v in zip(dpsi, dth, dgam, strict=True)]))
    rot = Rotation.from_rotvec(rng.uniform(-3e-4, 3e-4, (n, 3))).as_matrix()
    batch.append(rot)
    batch = np.stack(batch)  # (4, n, 3, 3)
    wx, wy = rate_sensing_error_from_rotation(batch, phi1_deg=p1, phi2_deg=p2)
    assert wx.shape == (4,)
    bf = BruteForce(p1, p2, DEFAULT_LATITUDE_DEG)
    for k in range(4):
        ref = bf.run(batch[k])
        assert wx[k] == pytest.approx(np.max(np.abs(ref["x"][1])), abs=1e-12)
        assert wy[k] == pytest.approx(np.max(np.abs(ref["y"][1])), abs=1e-12)


# ------------------------------------------------------------- conclusions (1)–(3) of §2.2


def _single(method, comp, h=ARCMIN):
    e = [0.0, 0.0, 0.0]
    e[COMPONENTS.index(comp)] = h
    return rate_sensing_error(*e, method=method)


def test_conclusion_1_gamma_barely_moves_x_and_psi_barely_moves_y():
    # one arcmin of each component alone (default plan, 45.75°)
    m = "coefficients"
    x = {c: float(_single(m, c)[0]) for c in COMPONENTS}
    y = {c: float(_single(m, c)[1]) for c in COMPONENTS}
    rx = x["gamma"] / max(x["psi"], x["theta"])
    ry = y["psi"] / max(y["theta"], y["gamma"])
    print(f"coefficients: Δωx per arcmin {x}; Δγ/max(Δψ, Δθ) = {rx:.3f}")
    print(f"coefficients: Δωy per arcmin {y}; Δψ/max(Δθ, Δγ) = {ry:.3f}")
    assert rx < 0.10 and ry < 0.05  # rotacal: 0.070 and 0.031
    # against the weaker of the two driving components the effect is ~10 %, not nil
    assert x["gamma"] / min(x["psi"], x["theta"]) < 0.12
    assert y["psi"] / min(y["theta"], y["gamma"]) < 0.12
    # the printed eq. (13) does not bear conclusion (1) out for the y axis
    ex = {c: float(_single("eq13", c)[0]) for c in COMPONENTS}
    ey = {c: float(_single("eq13", c)[1]) for c in COMPONENTS}
    print(f"eq13: Δωx {ex}; Δωy {ey}")
    assert ey["psi"] / max(ey["theta"], ey["gamma"]) > 0.3


@pytest.mark.parametrize("method", METHODS)
def test_conclusions_2_3_even_and_growing_surfaces(method):
    s = rate_error_surfaces(math.radians(0.05), n=41, method=method)
    for axis, plane in (("x", "psi_theta"), ("y", "theta_gamma")):
        z = s[axis][plane]
        top = z.max()
        # even in both components: exactly in the one that only enters linearly through a
        # position-symmetric column, to the quadratic order (< 10⁻³ of the peak) in the other
        asym = max(np.max(np.abs(z - z[::-1, :])), np.max(np.abs(z - z[:, ::-1])))
        assert asym < 1e-3 * top
        # grows with |first| and |second| away from 0 (tolerance: rounding)
        c = z.shape[0] // 2
        assert np.all(np.diff(z[c:, :], axis=0) >= -1e-15)
        assert np.all(np.diff(z[:, c:], axis=1) >= -1e-15)
        assert np.all(np.diff(z[: c + 1, :], axis=0) <= 1e-15)
        assert z[c, c] == 0.0
    # a point of the surface is the function's value
    g = s["grid_rad"]
    wx, _ = rate_sensing_error(g[3], g[30], 0.0, method=method)
    assert s["x"]["psi_theta"][3, 30] == pytest.approx(wx, rel=1e-14)
    wy = rate_sensing_error(0.0, 0.0, g[5], method=method)[1]
    assert s["curves"]["y"]["gamma"][5] == pytest.approx(wy, rel=1e-14)


# ----------------------------------------------------------------- eqs. (15)–(16), Figure 5


def _corners(lim):
    return np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * lim


@pytest.mark.parametrize("method", METHODS)
def test_orientation_requirement_meets_and_touches_0p01(method):
    r = orientation_requirement(0.01, method=method)
    assert isinstance(r, OrientationRequirement)
    lim = np.array([r.limits_rad[c] for c in COMPONENTS])
    print(f"{method}: box {r.limits_deg} deg, equal {r.equal_limit_deg:.5f} deg")
    bf = BruteForce(*_default_plan(), DEFAULT_LATITUDE_DEG, method=method)

    def worst(box):
        return max(
            np.max(np.abs(v[1])) for c in _corners(box) for v in bf.run(_literal_eq7(*c)).values()
        )

    top = worst(lim)
    assert top <= 0.01 + 1e-12
    assert top == pytest.approx(0.01, abs=1e-6)
    assert worst(1.01 * lim) > 0.01
    assert worst(np.full(3, r.equal_limit_rad)) == pytest.approx(0.01, abs=1e-6)
    assert worst(np.full(3, 1.01 * r.equal_limit_rad)) > 0.01
    # the box is larger than the equal cube (its volume is maximal)
    assert np.prod(lim) > r.equal_limit_rad**3
    # the corners are the worst points of the box: an interior grid never exceeds them
    g = [np.linspace(-v, v, 15) for v in lim]
    wx, wy = rate_sensing_error(*np.meshgrid(*g, indexing="ij"), method=method)
    assert max(wx.max(), wy.max()) <= 0.01 * (1 + 1e-12)
    assert r.rate_error_at_limits_deg_h["x"] <= 0.01 + 1e-15
    json.dumps(r.to_dict())


def _linear_response(method):
    """J (2n, 3) of Δω_vec (both axes) by central differences of the brute force."""
    bf = BruteForce(*_default_plan(), DEFAULT_LATITUDE_DEG, method=method)
    h = 1e-6
    cols = []
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        up, dn = bf.run(_literal_eq7(*e)), bf.run(_literal_eq7(*(-e)))
        cols.append(np.concatenate([(up[a][1] - dn[a][1]) / (2 * h) for a in ("x", "y")]))
    return np.abs(np.column_stack(cols))


@pytest.mark.parametrize("method", METHODS)
def test_limits_agree_with_the_linear_response(method):
    wm = 0.01
    r = orientation_requirement(wm, method=method)
    j = _linear_response(method)
    # the equal limit: Σ_j |J_ij|·I ≤ ωm for every row
    i_lin = wm / np.max(j.sum(axis=1))
    assert r.equal_limit_rad == pytest.approx(i_lin, rel=5e-4)
    # the box: a coarse-to-fine search over (Iψ, Iθ) with the largest feasible Iγ, linear model
    best = (-np.inf, None)
    lo, hi = np.log(i_lin / 20), np.log(i_lin * 20)
    c_psi, c_th = (lo + hi) / 2, (lo + hi) / 2
    span = (hi - lo) / 2
    for _ in range(6):
        xs = np.linspace(c_psi - span, c_psi + span, 81)
        ys = np.linspace(c_th - span, c_th + span, 81)
        ip, it = np.meshgrid(np.exp(xs), np.exp(ys), indexing="ij")
        rest = wm - ip[..., None] * j[:, 0] - it[..., None] * j[:, 1]
        with np.errstate(divide="ignore"):
            ig = np.where(j[:, 2] > 0, rest / j[:, 2], np.inf).min(axis=-1)
        ok = (rest.min(axis=-1) > 0) & (ig > 0)
        vol = np.where(ok, np.log(ip) + np.log(it) + np.log(np.where(ok, ig, 1.0)), -np.inf)
        k = np.unravel_index(np.argmax(vol), vol.shape)
        best = (vol[k], (ip[k], it[k], ig[k]))
        c_psi, c_th = xs[k[0]], ys[k[1]]
        span /= 8
    lim = np.array([r.limits_rad[c] for c in COMPONENTS])
    np.testing.assert_allclose(lim, best[1], rtol=2e-3)


def test_requirement_scales_with_the_accuracy():
    # Δω is linear to ~10⁻⁴ in the orientation error: halving ωm halves the limits
    a, b = orientation_requirement(0.01), orientation_requirement(0.005)
    for c in COMPONENTS:
        assert b.limits_rad[c] == pytest.approx(a.limits_rad[c] / 2, rel=1e-3)


# ----------------------------------------------------------------------------- user errors


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: rate_sensing_error(np.nan, 0, 0), "dpsi has 1 non-finite"),
        (lambda: rate_sensing_error(0, 0.5, 0), "dtheta reaches 0.5 rad"),
        (lambda: rate_sensing_error([0, 0], [0, 0, 0], 0), "must broadcast"),
        (lambda: rate_sensing_error(0, 0, 0, method="eq14"), "method must be one of"),
        (lambda: rate_sensing_error(0, 0, 0, phi1_deg=[0, 45]), "give both phi1_deg"),
        (lambda: rate_sensing_error(0, 0, 0, latitude_deg=95), "latitude_deg"),
        (lambda: rate_sensing_error(0, 0, 0, earth_rate_deg_h=-1), "earth_rate_deg_h"),
        (lambda: rate_sensing_error(0, 0, 0, coefficients={"z": {}}), "unknown axis 'z'"),
        (lambda: rate_sensing_error(0, 0, 0, coefficients={"x": {"Dyy": 1}}), "'Dyy'"),
        (lambda: rate_sensing_error(0, 0, 0, coefficients={"y": {"DF": math.inf}}), "finite"),
        (lambda: orientation_requirement(-0.01), "required_deg_h must be a positive"),
        (lambda: orientation_requirement(math.nan), "required_deg_h must be finite"),
        (lambda: rate_error_surfaces(0.0), "limit_rad"),
        (lambda: rate_error_surfaces(1e-3, n=1), "n must be an integer"),
    ],
)
def test_bad_settings_raise_one_line_config_errors(call, match):
    with pytest.raises(ConfigError, match=match) as exc:
        call()
    assert "\n" not in str(exc.value)


def test_plans_that_do_not_identify_the_coefficients_are_refused():
    g = np.arange(0.0, 360.0, 90.0)
    p1, p2 = (v.ravel() for v in np.meshgrid(g, g, indexing="ij"))  # ax·ay ≡ 0
    with pytest.raises(ConfigError, match="unidentifiable"):
        rate_sensing_error(1e-4, 0, 0, phi1_deg=p1, phi2_deg=p2)
    with pytest.raises(ConfigError, match="unidentifiable"):
        orientation_requirement(0.01, phi1_deg=p1, phi2_deg=p2)
    with pytest.raises(ConfigError, match="distinct turntable position"):
        rate_sensing_error(1e-4, 0, 0, phi1_deg=[0, 45], phi2_deg=[0, 0])


def test_bad_rotation_arrays_are_refused():
    p1, p2 = _default_plan()
    with pytest.raises(ConfigError, match=r"shape \(\.\.\., 64, 3, 3\)"):
        rate_sensing_error_from_rotation(np.eye(3), phi1_deg=p1, phi2_deg=p2)
    with pytest.raises(ConfigError, match=r"shape \(\.\.\., 64, 3, 3\)"):
        rate_sensing_error_from_rotation(np.zeros((5, 3, 3)), phi1_deg=p1, phi2_deg=p2)
    bad = np.broadcast_to(np.eye(3), (64, 3, 3)).copy()
    bad[3, 0, 0] = np.nan
    with pytest.raises(ConfigError, match="non-finite"):
        rate_sensing_error_from_rotation(bad, phi1_deg=p1, phi2_deg=p2)
    rz = Rotation.from_euler("z", 30, degrees=True).as_matrix()
    with pytest.raises(ConfigError, match="not R_t"):
        rate_sensing_error_from_rotation(np.broadcast_to(rz, (64, 3, 3)), phi1_deg=p1, phi2_deg=p2)
