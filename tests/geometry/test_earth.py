"""WGS-84 Earth model against published constants and closed-form geometry.

Expected values come from the WGS-84 definition (NIMA TR8350.2, 3rd ed.: a, 1/f, GM, omega,
normal gravity on the equator and at the pole), from the geometry of an ellipse of
revolution, and from the standard free-air gradient; never from `earth` itself.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core.geometry import earth

# WGS-84 defining / derived constants, typed in from TR8350.2 (not imported from the module)
WGS_A = 6378137.0
WGS_INV_F = 298.257223563
WGS_B = WGS_A * (1.0 - 1.0 / WGS_INV_F)             # 6356752.3142 m
GAMMA_E = 9.7803253359                              # normal gravity on the equator, m/s^2
GAMMA_P = 9.8321849379                              # normal gravity at the poles, m/s^2
SIDEREAL_DAY_S = 86164.0905                          # Earth rotation period w.r.t. the stars
FREE_AIR_GRADIENT = -3.086e-6                        # 0.3086 mGal/m, s^-2

# one unit in the last place of an ECEF coordinate (|p| ~ 6.4e6 m) is 9.3e-10 m, and one ulp of
# a latitude near 1 rad (2.2e-16 rad) is 1.4e-9 m on the ground: a geodetic <-> ECEF round trip
# cannot be better than a few nanometres in double precision. Checked to 5 ulps (4.7e-9 m).
ECEF_ULP = np.spacing(WGS_A)
ROUND_TRIP_TOL_M = 5 * ECEF_ULP


def test_normal_gravity_equator_and_pole():
    assert earth.gravity(0.0, 0.0) == pytest.approx(GAMMA_E, abs=1e-10)
    assert earth.gravity(np.pi / 2, 0.0) == pytest.approx(GAMMA_P, abs=1e-10)
    assert earth.gravity(-np.pi / 2, 0.0) == pytest.approx(GAMMA_P, abs=1e-10)


def test_normal_gravity_somigliana_at_any_latitude():
    # Somigliana's closed form, with its constant built from the published gamma_e, gamma_p:
    # gamma = (a gamma_e cos^2 + b gamma_p sin^2) / sqrt(a^2 cos^2 + b^2 sin^2)
    lat = np.linspace(-np.pi / 2, np.pi / 2, 37)
    c2, s2 = np.cos(lat) ** 2, np.sin(lat) ** 2
    expected = (WGS_A * GAMMA_E * c2 + WGS_B * GAMMA_P * s2) / np.sqrt(WGS_A**2 * c2 + WGS_B**2 * s2)
    np.testing.assert_allclose(earth.gravity(lat, 0.0), expected, rtol=0, atol=2e-10)


@pytest.mark.parametrize('lat_deg', [0.0, 30.0, 45.0, 60.0, 90.0])
def test_free_air_gradient(lat_deg):
    lat = np.radians(lat_deg)
    dgdh = (earth.gravity(lat, 1.0) - earth.gravity(lat, -1.0)) / 2.0
    # the standard free-air gradient -0.3086 mGal/m; it varies by +-0.1 % with latitude
    assert dgdh == pytest.approx(FREE_AIR_GRADIENT, rel=2e-3)
    # and over a few km the change stays linear to the same accuracy (h^2 term is 1e-3 of it)
    dg = earth.gravity(lat, 3000.0) - earth.gravity(lat, 0.0)
    assert dg == pytest.approx(3000.0 * FREE_AIR_GRADIENT, rel=3e-3)


def test_gravity_vector_points_down():
    g = earth.gravity_n(np.radians([0.0, 40.0]), np.array([0.0, 100.0]))
    assert g.shape == (2, 3)
    np.testing.assert_array_equal(g[:, :2], 0.0)
    assert np.all(g[:, 2] < -9.7)


def test_radii_of_curvature_closed_form():
    # ellipse of revolution: R_N(0) = a, R_M(0) = b^2 / a, R_M(90) = R_N(90) = a^2 / b
    r_m, r_n = earth.radii(0.0)
    assert r_n == pytest.approx(WGS_A, rel=1e-15)
    assert r_m == pytest.approx(WGS_B**2 / WGS_A, rel=1e-14)
    r_m, r_n = earth.radii(np.pi / 2)
    assert r_m == pytest.approx(WGS_A**2 / WGS_B, rel=1e-14)
    assert r_n == pytest.approx(WGS_A**2 / WGS_B, rel=1e-14)


def test_radii_against_ellipse_geometry():
    # R_N is the length of the normal from the surface to the polar axis: rho / cos(lat);
    # R_M is the radius of curvature of the meridian ellipse: (a b)^2 / (a^2 sin^2 + b^2 cos^2)^1.5
    # (parametrised by geodetic latitude, rho = a^2 cos / sqrt(a^2 cos^2 + b^2 sin^2))
    lat = np.radians(np.linspace(-85.0, 85.0, 35))
    c, s = np.cos(lat), np.sin(lat)
    den = np.sqrt(WGS_A**2 * c**2 + WGS_B**2 * s**2)
    rho = WGS_A**2 * c / den
    r_m, r_n = earth.radii(lat)
    np.testing.assert_allclose(r_n, rho / c, rtol=1e-14)
    np.testing.assert_allclose(r_m, (WGS_A * WGS_B) ** 2 / den**3, rtol=1e-13)



def test_the_transverse_radius_alone_is_radii_s():
    """The geodetic iteration's R_N without R_M: the same bits and type as radii's, arrays and floats."""
    lat = np.random.default_rng(2).uniform(-1.57, 1.57, 1000)
    assert earth.transverse_radius(lat).tobytes() == earth.radii(lat)[1].tobytes()
    for x in (0.0, -0.7, np.float64(1.2)):
        a, b = earth.radii(x)[1], earth.transverse_radius(x)
        assert type(a) is type(b) and np.float64(a).tobytes() == np.float64(b).tobytes()


def test_geodetic_to_ecef_known_points():
    np.testing.assert_allclose(earth.geodetic_to_ecef(0.0, 0.0, 0.0), [WGS_A, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(earth.geodetic_to_ecef(0.0, np.pi / 2, 0.0), [0.0, WGS_A, 0.0], atol=1e-9)
    np.testing.assert_allclose(earth.geodetic_to_ecef(np.pi / 2, 0.3, 0.0), [0.0, 0.0, WGS_B], atol=1e-8)
    np.testing.assert_allclose(earth.geodetic_to_ecef(-np.pi / 2, 0.3, 10.0), [0.0, 0.0, -WGS_B - 10.0],
                               atol=1e-8)


def test_geodetic_to_ecef_on_ellipsoid_and_height_along_normal():
    rng = np.random.default_rng(11)
    lat = rng.uniform(-np.pi / 2, np.pi / 2, 200)
    lon = rng.uniform(-np.pi, np.pi, 200)
    p0 = earth.geodetic_to_ecef(lat, lon, 0.0)
    # on the ellipsoid x^2/a^2 + y^2/a^2 + z^2/b^2 = 1
    q = (p0[:, 0] ** 2 + p0[:, 1] ** 2) / WGS_A**2 + p0[:, 2] ** 2 / WGS_B**2
    np.testing.assert_allclose(q, 1.0, atol=1e-15 * 8)
    # the geodetic normal (cos lat cos lon, cos lat sin lon, sin lat) is the ellipsoid's normal
    n = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)
    grad = np.stack([p0[:, 0] / WGS_A**2, p0[:, 1] / WGS_A**2, p0[:, 2] / WGS_B**2], axis=-1)
    grad /= np.linalg.norm(grad, axis=-1, keepdims=True)
    np.testing.assert_allclose(grad, n, atol=1e-14)
    # height is measured along that normal
    p1 = earth.geodetic_to_ecef(lat, lon, 1234.5)
    np.testing.assert_allclose(p1 - p0, 1234.5 * n, atol=4 * ECEF_ULP)


def test_geodetic_ecef_round_trip():
    rng = np.random.default_rng(12)
    n = 2000
    lat = rng.uniform(np.radians(-89.99), np.radians(89.99), n)
    lon = rng.uniform(-np.pi, np.pi, n)
    h = rng.uniform(-1000.0, 20000.0, n)
    p = earth.geodetic_to_ecef(lat, lon, h)
    lat2, lon2, h2 = earth.ecef_to_geodetic(p)
    r_m, r_n = earth.radii(lat)
    # geodetic differences expressed in metres
    err = np.abs(np.stack([(lat2 - lat) * (r_m + h), (lon2 - lon) * (r_n + h) * np.cos(lat),
                           h2 - h], axis=-1))
    assert err.max() < ROUND_TRIP_TOL_M
    # ECEF -> geodetic -> ECEF
    p2 = earth.geodetic_to_ecef(lat2, lon2, h2)
    assert np.linalg.norm(p2 - p, axis=-1).max() < ROUND_TRIP_TOL_M


def test_ecef_to_enu_axes_are_geodetic_directions():
    # east = d p / d lon normalised, north = d p / d lat normalised, up = the ellipsoid normal
    lat, lon, d = np.radians(40.0), np.radians(116.0), 1e-7
    c = earth.c_ecef_to_enu(lat, lon)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-15)
    east = earth.geodetic_to_ecef(lat, lon + d, 0.0) - earth.geodetic_to_ecef(lat, lon - d, 0.0)
    north = earth.geodetic_to_ecef(lat + d, lon, 0.0) - earth.geodetic_to_ecef(lat - d, lon, 0.0)
    up = earth.geodetic_to_ecef(lat, lon, 1.0) - earth.geodetic_to_ecef(lat, lon, -1.0)
    for row, v in zip(c, (east, north, up)):
        np.testing.assert_allclose(row, v / np.linalg.norm(v), atol=1e-8)


def test_tangent_plane_geometry_and_round_trip():
    lat0, lon0, h0 = np.radians(40.0), np.radians(116.0), 5.0
    tp = earth.TangentPlane(lat0, lon0, h0)
    np.testing.assert_allclose(tp.from_geodetic(lat0, lon0, h0), 0.0, atol=4 * ECEF_ULP)
    # straight up the local normal
    np.testing.assert_allclose(tp.from_geodetic(lat0, lon0, h0 + 100.0), [0.0, 0.0, 100.0],
                               atol=4 * ECEF_ULP)
    # a small step north / east: R_M dlat, (R_N + h) cos(lat) dlon (second order ~1e-6 m)
    r_m, r_n = earth.radii(lat0)
    dl = 1e-6
    np.testing.assert_allclose(tp.from_geodetic(lat0 + dl, lon0, h0), [0.0, (r_m + h0) * dl, 0.0],
                               atol=1e-5)
    np.testing.assert_allclose(tp.from_geodetic(lat0, lon0 + dl, h0),
                               [(r_n + h0) * np.cos(lat0) * dl, 0.0, 0.0], atol=1e-5)
    # round trip over +-50 km, +-5 km
    rng = np.random.default_rng(13)
    enu = rng.uniform([-5e4, -5e4, -5e3], [5e4, 5e4, 5e3], (500, 3))
    back = tp.from_geodetic(*tp.to_geodetic(enu))
    assert np.abs(back - enu).max() < ROUND_TRIP_TOL_M
    # and a rigid transform: distances are preserved
    lat, lon, h = tp.to_geodetic(enu)
    p = earth.geodetic_to_ecef(lat, lon, h)
    np.testing.assert_allclose(np.linalg.norm(p[1:] - p[:-1], axis=-1),
                               np.linalg.norm(enu[1:] - enu[:-1], axis=-1), atol=8 * ECEF_ULP)


def test_earth_rate():
    omega = 2.0 * np.pi / SIDEREAL_DAY_S
    lat = np.radians(np.linspace(-89.0, 89.0, 19))
    w = earth.omega_ie_n(lat)
    np.testing.assert_allclose(np.linalg.norm(w, axis=-1), omega, rtol=1e-6)
    # the Earth's axis in ENU: (0, cos lat, sin lat); nothing along East
    np.testing.assert_allclose(w / np.linalg.norm(w, axis=-1, keepdims=True),
                               np.stack([0 * lat, np.cos(lat), np.sin(lat)], axis=-1), atol=1e-15)
    # same vector as the ECEF spin axis rotated into ENU
    c = earth.c_ecef_to_enu(np.radians(40.0), np.radians(-70.0))
    np.testing.assert_allclose(earth.omega_ie_n(np.radians(40.0)), c @ [0.0, 0.0, earth.OMEGA_IE],
                               atol=1e-18)


def test_transport_rate():
    # moving east at v along a parallel turns the nav frame about the Earth's axis at
    # v / ((R_N + h) cos lat); moving north turns it about -East at v / (R_M + h)
    lat, h, v = np.radians(40.0), 2000.0, 150.0
    c, s = np.cos(lat), np.sin(lat)
    den = np.sqrt(WGS_A**2 * c**2 + WGS_B**2 * s**2)
    r_n = WGS_A**2 / den
    r_m = (WGS_A * WGS_B) ** 2 / den**3
    rate = v / ((r_n + h) * c)
    np.testing.assert_allclose(earth.omega_en_n(lat, h, [v, 0.0, 0.0]), [0.0, rate * c, rate * s],
                               rtol=1e-13, atol=1e-20)
    np.testing.assert_allclose(earth.omega_en_n(lat, h, [0.0, v, 0.0]), [-v / (r_m + h), 0.0, 0.0],
                               rtol=1e-13, atol=1e-20)
    np.testing.assert_array_equal(earth.omega_en_n(lat, h, [0.0, 0.0, 7.0]), 0.0)


@pytest.mark.parametrize('lat_deg,h,v', [(0.0, 0.0, (0.0, 0.0, 0.0)), (40.0, 120.0, (5.0, 8.0, 0.3)),
                                         (-65.0, 3000.0, (-150.0, 60.0, -2.0))])
def test_local_terms_fast_path(lat_deg, h, v):
    """The strapdown's scalar path: radii, Earth and transport rates and |g| from the same
    closed forms as above (ellipse geometry, Somigliana with the free-air terms)."""
    lat = np.radians(lat_deg)
    c, s = np.cos(lat), np.sin(lat)
    den = np.sqrt(WGS_A**2 * c**2 + WGS_B**2 * s**2)
    r_n, r_m = WGS_A**2 / den, (WGS_A * WGS_B) ** 2 / den**3
    got_rm, got_rn, wie_n, wie_u, wen_e, wen_n, wen_u, g = earth.local_terms(lat, h, v[0], v[1])
    w_ie, w_en = np.array([0.0, wie_n, wie_u]), np.array([wen_e, wen_n, wen_u])
    assert got_rm == pytest.approx(r_m, rel=1e-13)
    assert got_rn == pytest.approx(r_n, rel=1e-13)
    omega = 2.0 * np.pi / SIDEREAL_DAY_S
    np.testing.assert_allclose(w_ie, omega * np.array([0.0, c, s]), rtol=1e-6, atol=1e-20)
    np.testing.assert_allclose(w_en, [-v[1] / (r_m + h), v[0] / (r_n + h), v[0] * s / c / (r_n + h)],
                               rtol=1e-12, atol=1e-20)
    g0 = (WGS_A * GAMMA_E * c**2 + WGS_B * GAMMA_P * s**2) / den
    assert earth.local_terms(lat, 0.0, v[0], v[1])[7] == pytest.approx(g0, abs=2e-10)
    # free-air change, to the same 0.3 % as test_free_air_gradient
    assert g - g0 == pytest.approx(FREE_AIR_GRADIENT * h, rel=3e-3, abs=1e-12)


def _eight_passes_over_every_point(p):
    """The geodetic iteration as first written: eight passes over every point."""
    p = np.asarray(p, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    lon = np.arctan2(y, x)
    rho = np.hypot(x, y)
    lat = np.arctan2(z, rho * (1.0 - earth.E2))
    h = np.zeros_like(rho)
    for _ in range(8):
        r_n = earth.transverse_radius(lat)
        h = rho / np.cos(lat) - r_n
        lat = np.arctan2(z, rho * (1.0 - earth.E2 * r_n / (r_n + h)))
    return lat, lon, h


@pytest.mark.parametrize('shape', [(3,), (1, 3), (2, 3), (17, 3), (301, 3), (40, 3, 3), (30000, 3)])
def test_geodetic_iteration_gives_the_bits_of_eight_passes_over_every_point(shape):
    """Iterating only the points still moving after the fourth pass gives, bit for bit and of the
    same types, what eight passes over every point give: near the surface, up to thousands of km
    away, at a pole and the centre, and with NaN and inf coordinates."""
    rng = np.random.default_rng(sum(shape))
    plane = earth.TangentPlane(np.radians(36.9), np.radians(-76.3), 0.0)
    enu = rng.standard_normal(shape) * np.array([2e4, 2e4, 50.0]) * rng.uniform(0.001, 300.0, shape[:-1] + (1,))
    p = plane.origin + enu @ plane.c
    if p.ndim == 2 and len(p) >= 17:
        p[0], p[1], p[2] = (0.0, 0.0, earth.B), (0.0, 0.0, 0.0), (0.0, 0.0, -earth.B - 10.0)
        p[3, 0], p[4, 2], p[5, 1] = np.nan, np.inf, -np.inf
    with np.errstate(all='ignore'):                # the centre divides by zero, NaN and inf propagate
        got, want = earth.ecef_to_geodetic(p), _eight_passes_over_every_point(p)
    for g, w in zip(got, want):
        assert type(g) is type(w) and np.shape(g) == np.shape(w)
        assert np.asarray(g).tobytes() == np.asarray(w).tobytes()


def test_plane_batch_equals_points_one_at_a_time():
    """to_geodetic and from_geodetic_rows on K points give what K one-point calls give, bit for
    bit (the aircraft truth is computed in chunks of any size by the slave node)."""
    plane = earth.TangentPlane(np.radians(30.0), np.radians(120.0), 0.0)
    rng = np.random.default_rng(4)
    p = rng.standard_normal((301, 3)) * np.array([5e4, 5e4, 3e3])
    lat, lon, h = plane.to_geodetic(p)
    one = [plane.to_geodetic(p[i:i + 1]) for i in range(len(p))]
    for j, x in enumerate((lat, lon, h)):
        assert x.tobytes() == np.concatenate([o[j] for o in one]).tobytes()
    back = plane.from_geodetic_rows(lat, lon, h)
    one_back = np.concatenate([plane.from_geodetic_rows(lat[i:i + 1], lon[i:i + 1], h[i:i + 1])
                               for i in range(len(p))])
    assert back.tobytes() == one_back.tobytes()
    np.testing.assert_allclose(back, p, atol=1e-6)


def test_one_points_rates_and_position_are_the_array_forms_bits():
    """nav_rate_point and TangentPlane.from_geodetic_point (the filter's outputs, one point at a
    time, in Python floats) against omega_ie_n + omega_en_n and from_geodetic, bit for bit, over
    latitudes, heights and velocities whose powers and tangents round differently in the C
    library and numpy (x**2 against x * x, numpy's tan against the C library's)."""
    rng = np.random.default_rng(4)
    plane = earth.TangentPlane(0.61, -1.2, 3.0)
    lat = np.r_[rng.uniform(-1.5, 1.5, 3000), 0.0, -0.0, 1e-300]
    lon = np.r_[rng.uniform(-3.1, 3.1, 3000), 0.0, -0.0, 3.0]
    h = np.r_[rng.normal(0.0, 500.0, 3000), 0.0, -0.0, 1e4]
    v = np.r_[rng.normal(0.0, 30.0, (3000, 3)), [[0.0, -0.0, 0.0], [-0.0, 0.0, -0.0], [1.0, 2.0, 3.0]]]
    assert sum(float(np.tan(x)) != math.tan(x) for x in lat.tolist()) > 0     # the case is met
    for a, o, z, vel in zip(lat.tolist(), lon.tolist(), h.tolist(), v):
        want = earth.omega_ie_n(a) + earth.omega_en_n(a, z, vel)
        got = np.array(earth.nav_rate_point(a, z, float(vel[0]), float(vel[1])))
        assert got.tobytes() == want.tobytes(), (a, z, vel)
        assert plane.from_geodetic_point(a, o, z).tobytes() == plane.from_geodetic(a, o, z).tobytes(), (a, o, z)


def test_one_point_at_an_infinite_latitude_or_longitude_gives_the_array_forms_nans():
    """The C library's sine raises on an infinite angle where numpy gives NaN: a diverged slave's
    odometry must come out non-finite (and be caught as such), not raise."""
    plane = earth.TangentPlane(0.61, -1.2, 3.0)
    v = np.array([1.0, 2.0, 0.0])
    for lat, lon in ((math.inf, 0.3), (-math.inf, 0.3), (0.6, math.inf), (0.6, -math.inf), (math.nan, 0.3)):
        with np.errstate(invalid='ignore'):
            want_rate = earth.omega_ie_n(lat) + earth.omega_en_n(lat, 10.0, v)
            want_pos = plane.from_geodetic(lat, lon, 10.0)
            assert np.array(earth.nav_rate_point(lat, 10.0, 1.0, 2.0)).tobytes() == want_rate.tobytes()
            assert plane.from_geodetic_point(lat, lon, 10.0).tobytes() == want_pos.tobytes()
        assert not np.all(np.isfinite(want_pos))
