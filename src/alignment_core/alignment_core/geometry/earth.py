"""WGS-84 Earth model in the local-level East-North-Up navigation frame.

Radii, normal gravity (Somigliana with the free-air height term), Earth rate and transport
rate, and the geodetic <-> ECEF <-> local tangent-plane conversions used for world poses.
"""
from __future__ import annotations

import math

import numpy as np

from alignment_core.geometry.rotations import rows_matmul

A = 6378137.0                      # semi-major axis, m
F = 1.0 / 298.257223563            # flattening
E2 = F * (2.0 - F)                 # first eccentricity squared
OMEGA_IE = 7.292115e-5             # Earth rotation rate, rad/s
GM = 3.986004418e14                # m^3/s^2
G_EQUATOR = 9.7803253359           # normal gravity on the equator, m/s^2
K_SOMIGLIANA = 0.00193185265241
B = A * (1.0 - F)
M_RATIO = OMEGA_IE**2 * A**2 * B / GM


def radii(lat: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Meridian (R_M) and transverse (R_N) radii of curvature at latitude `lat` (rad)."""
    s2 = np.sin(lat) ** 2
    den = 1.0 - E2 * s2
    r_n = A / np.sqrt(den)
    r_m = A * (1.0 - E2) / den**1.5
    return r_m, r_n


def transverse_radius(lat: float | np.ndarray) -> np.ndarray:
    """R_N of `radii`, its bits, without R_M's power (the geodetic iteration needs R_N alone)."""
    return A / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)


def gravity(lat: float | np.ndarray, h: float | np.ndarray) -> np.ndarray:
    """Normal gravity magnitude (m/s^2) at latitude `lat` (rad) and height `h` (m)."""
    s2 = np.sin(lat) ** 2
    g0 = G_EQUATOR * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h + 3.0 / A**2 * h**2)


def gravity_n(lat, h) -> np.ndarray:
    """Gravity vector in ENU, shape (..., 3)."""
    g = np.asarray(gravity(lat, h), dtype=float)
    out = np.zeros(g.shape + (3,))
    out[..., 2] = -g
    return out


def omega_ie_n(lat) -> np.ndarray:
    """Earth rate in ENU, shape (..., 3)."""
    lat = np.asarray(lat, dtype=float)
    out = np.zeros(lat.shape + (3,))
    out[..., 1] = OMEGA_IE * np.cos(lat)
    out[..., 2] = OMEGA_IE * np.sin(lat)
    return out


def omega_en_n(lat, h, v_n) -> np.ndarray:
    """Transport rate in ENU for ground velocity `v_n` (..., 3)."""
    v_n = np.asarray(v_n, dtype=float)
    r_m, r_n = radii(lat)
    out = np.empty(v_n.shape)
    out[..., 0] = -v_n[..., 1] / (r_m + h)
    out[..., 1] = v_n[..., 0] / (r_n + h)
    out[..., 2] = v_n[..., 0] * np.tan(lat) / (r_n + h)
    return out


def nav_rate_point(lat: float, h: float, v_e: float, v_n: float) -> tuple[float, float, float]:
    """omega_ie_n(lat) + omega_en_n(lat, h, v) of one point, ENU, in Python floats: the array
    forms' bits (a numpy scalar's power is the C library's pow, as a Python float's is; the
    tangent is numpy's own, which differs from the C library's in the last bit now and then).
    An infinite latitude gives the array forms' NaNs (the C library's sine raises on it)."""
    if not math.isfinite(lat):
        e, n, u = (omega_ie_n(lat) + omega_en_n(lat, h, np.array([v_e, v_n, 0.0]))).tolist()
        return e, n, u
    sl = math.sin(lat)
    den = 1.0 - E2 * sl**2
    r_n = A / math.sqrt(den)
    r_m = A * (1.0 - E2) / den**1.5
    return (0.0 + -v_n / (r_m + h), OMEGA_IE * math.cos(lat) + v_e / (r_n + h),
            OMEGA_IE * sl + v_e * float(np.tan(lat)) / (r_n + h))


def geodetic_to_ecef(lat, lon, h) -> np.ndarray:
    """ECEF position (..., 3) of geodetic coordinates (rad, rad, m)."""
    _, r_n = radii(lat)
    cl, sl = np.cos(lat), np.sin(lat)
    return np.stack([(r_n + h) * cl * np.cos(lon), (r_n + h) * cl * np.sin(lon),
                     (r_n * (1.0 - E2) + h) * sl], axis=-1)


GEODETIC_PASSES = 8                # passes of the geodetic iteration
_EVERY_POINT_PASSES = 4            # of which every point takes part in the first four


def ecef_to_geodetic(p) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Geodetic (lat, lon, h) of ECEF points (..., 3); iterative, to a few nm (double precision).
    Each pass maps a point's latitude to the next. A pass that leaves it unchanged has reached its
    fixed point, and every later pass gives the same bits, so after the fourth pass only the
    points still moving are iterated (fewer than half of them on a ship's track): the numbers of
    eight passes over every point."""
    p = np.asarray(p, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    lon = np.arctan2(y, x)
    rho = np.hypot(x, y)
    shape = rho.shape
    rho, z = rho.ravel(), z.ravel()
    lat = np.arctan2(z, rho * (1.0 - E2))
    prev = lat
    for _ in range(_EVERY_POINT_PASSES):
        prev = lat
        lat, h = _geodetic_pass(prev, rho, z)
    moving = np.flatnonzero(lat != prev)             # a NaN never stops: it takes every pass
    for _ in range(GEODETIC_PASSES - _EVERY_POINT_PASSES):
        if not len(moving):
            break
        prev = lat[moving]
        lat[moving], h[moving] = _geodetic_pass(prev, rho[moving], z[moving])
        moving = moving[lat[moving] != prev]
    return lat.reshape(shape)[()], lon, h.reshape(shape)[()]


def _geodetic_pass(lat: np.ndarray, rho: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One pass of the geodetic iteration on points (K,): (the next latitude, the height at lat)."""
    r_n = transverse_radius(lat)
    h = rho / np.cos(lat) - r_n
    return np.arctan2(z, rho * (1.0 - E2 * r_n / (r_n + h))), h


def c_ecef_to_enu(lat, lon) -> np.ndarray:
    """Rotation matrix (3, 3) from ECEF to the ENU frame at (lat, lon)."""
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    return np.array([[-so, co, 0.0], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]])


class TangentPlane:
    """Local ENU tangent plane at a fixed origin: the `world` frame of the poses we publish."""

    def __init__(self, lat0: float, lon0: float, h0: float = 0.0) -> None:
        self.origin = geodetic_to_ecef(lat0, lon0, h0)
        self.c = c_ecef_to_enu(lat0, lon0)

    def from_geodetic(self, lat, lon, h) -> np.ndarray:
        """World points (..., 3) of geodetic coordinates; K points (K, 3) with the bits they have in
        any batch of two or more (numpy's product of a single row is a matrix-vector product, which
        rounds unlike the matrix product's fused multiply-adds): a ship evaluated in chunks of any
        size, one sample included, gives the whole run's numbers."""
        d = geodetic_to_ecef(lat, lon, h) - self.origin
        if d.ndim == 2 and len(d) == 1:
            return (np.concatenate([d, d]) @ self.c.T)[:1]
        return d @ self.c.T

    def from_geodetic_point(self, lat: float, lon: float, h: float) -> np.ndarray:
        """from_geodetic of one point (3,), its bits, the geodetic terms in Python floats (an
        infinite latitude or longitude: from_geodetic's NaNs, where the C library's sine raises)."""
        if not (math.isfinite(lat) and math.isfinite(lon)):
            return self.from_geodetic(lat, lon, h)
        sl, cl = math.sin(lat), math.cos(lat)
        r_n = A / math.sqrt(1.0 - E2 * sl**2)
        ecef = np.array([(r_n + h) * cl * math.cos(lon), (r_n + h) * cl * math.sin(lon), (r_n * (1.0 - E2) + h) * sl])
        return (ecef - self.origin) @ self.c.T

    def from_geodetic_rows(self, lat, lon, h) -> np.ndarray:
        """from_geodetic with each of K points (lat, lon, h of shape (K,)) computed alone
        (rotations.rows_matmul): K points give what K one-point calls give, bit for bit (the
        aircraft truth, stepped or in chunks). from_geodetic keeps the ship models' numbers."""
        return rows_matmul(geodetic_to_ecef(lat, lon, h) - self.origin, self.c.T)

    def to_geodetic(self, enu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Geodetic (lat, lon, h) of world points (..., 3); K points (K, 3) row by row
        (rotations.rows_matmul), so a batch equals its points one at a time, bit for bit."""
        return ecef_to_geodetic(rows_matmul(np.asarray(enu), self.c) + self.origin)

    def c_local_to_world(self, p_w) -> np.ndarray:
        """(..., 3, 3) rotation from the local-level ENU frame at world point(s) p_w (..., 3) to
        the world axes (they differ by distance / Earth radius: 1e-3 rad at 6 km)."""
        lat, lon, _ = self.to_geodetic(p_w)
        sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
        z = np.zeros_like(lat)
        c_el = np.stack([np.stack([-so, co, z], -1), np.stack([-sl * co, -sl * so, cl], -1),
                         np.stack([cl * co, cl * so, sl], -1)], -2)       # ECEF -> local ENU
        return self.c @ np.swapaxes(c_el, -1, -2)


def local_terms(lat: float, h: float, v_e: float, v_n: float
                ) -> tuple[float, float, float, float, float, float, float, float]:
    """Scalar fast path for the strapdown, in plain floats (no arrays: a 3-vector numpy op
    costs ~1 us, a float operation ~30 ns): (R_M, R_N, omega_ie^n north and up (east is 0),
    omega_en^n east, north and up, |g|) at latitude `lat`, height `h` and ENU velocity
    (v_e, v_n, .)."""
    sl, cl = math.sin(lat), math.cos(lat)
    s2 = sl * sl
    den = 1.0 - E2 * s2
    sq = math.sqrt(den)
    r_n = A / sq
    r_m = A * (1.0 - E2) / (den * sq)
    g0 = G_EQUATOR * (1.0 + K_SOMIGLIANA * s2) / sq
    g = g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h + 3.0 / A**2 * h * h)
    return (r_m, r_n, OMEGA_IE * cl, OMEGA_IE * sl,
            -v_n / (r_m + h), v_e / (r_n + h), v_e * (sl / cl) / (r_n + h), g)
