"""filter.flexure_states false (seed003_21 / seed003_24 without theta, theta'): the same model
with the flexure rows and columns taken out, its sigma free to be zero, refused where there is
no flexure; and it aligns a rigid mount."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import Corrections, Match, Propagation
from alignment_core.estimation.models.seed003 import Seed003VelocityAttitude
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN
from alignment_core.validation import ConfigError

FLEX = list(range(15, 21))


def _models(master: bool):
    full = Seed003VelocityAttitude(FilterConfig(model='seed003_24' if master else 'seed003_21'), master)
    rigid = Seed003VelocityAttitude(FilterConfig(model='seed003_24' if master else 'seed003_21',
                                                 flexure_states=False, flexure_sigma_arcmin=(0.0, 0.0, 0.0)), master)
    keep = [i for i in range(full.n) if i not in FLEX]
    return full, rigid, keep


@pytest.mark.parametrize('master', [False, True])
def test_the_model_without_flexure_is_the_full_one_without_its_rows(master):
    full, rigid, keep = _models(master)
    assert rigid.n == full.n - 6 and rigid.labels == tuple(full.labels[i] for i in keep)
    c = Rotation.from_euler('ZYX', [33.0, 2.5, -4.0], degrees=True).as_matrix()
    q = Rotation.from_matrix(c).as_quat()
    p = Propagation(c, np.array([0.1, -0.2, 9.8]), np.array([0.0, 5e-5, 4e-5]), np.array([1e-6, 0, 0]),
                    np.array([3.0, 4.0, 0.1]), 0.7, 10.0, 0.01)
    ix = np.ix_(keep, keep)
    np.testing.assert_array_equal(rigid.transition(p), full.transition(p)[ix])
    np.testing.assert_array_equal(rigid.process_noise(0.01), full.process_noise(0.01)[ix])
    np.testing.assert_array_equal(rigid.initial_covariance(), full.initial_covariance()[ix])
    m = Match(c_m=c, w_m=np.array([0.02, -0.01, 0.005]), r=np.array([40.0, -10, 15]), u_n=np.array([0.1, 0.2, 0.3]),
              v_ref=np.zeros(3), z_vel=np.array([0.01, 0.02, 0.03]), r_vel=np.eye(3) * 1e-4,
              ins=NavState(q_nb=q, v_n=np.zeros(3), lat=0.7, lon=2.0, h=0.0))
    corr = Corrections(mu=np.array([1.0, -2.0, 3.0]) * ARCMIN)
    a, b = full.measurement(m, corr), rigid.measurement(m, corr)
    np.testing.assert_array_equal(b.z, a.z)
    np.testing.assert_array_equal(b.matrix(), a.matrix()[:, keep])
    np.testing.assert_array_equal(b.r, a.r)


def test_validation():
    FilterConfig(model='seed003_21', flexure_states=False, flexure_sigma_arcmin=(0.0, 0.0, 0.0)).validate()
    with pytest.raises(ConfigError, match='flexure_sigma_arcmin'):
        FilterConfig(model='seed003_21', flexure_sigma_arcmin=(0.0, 0.0, 0.0)).validate()
    with pytest.raises(ConfigError, match='only seed003_21, seed003_24 have flexure states'):
        FilterConfig(model='vm15', flexure_states=False).validate()


def test_seed003_21_without_flexure_aligns_a_rigid_mount():
    """The deck scenario (the aircraft rigid on the deck, no flexure in the truth), 60 s: the
    mounting estimate within 3 sigma of the truth on every axis, and the default numbers with
    flexure states are not those without."""
    sc = scenario.load('deck_paper', overrides={'duration_s': 60.0, 'filter.model': 'seed003_21',
                                          'filter.flexure_states': False})
    inp = pipeline.simulate(sc)
    f = pipeline.align(sc, inp)
    e = f.outputs[-1]
    assert f.n_states == 15 and not any('flexure' in n for n in f.state_labels)
    err = e.misalignment - inp.sensor_truth['mounting']
    assert np.all(np.abs(err) < 3 * e.misalignment_sigma), (err / ARCMIN, e.misalignment_sigma / ARCMIN)
    flex = pipeline.align(dataclasses.replace(sc, filter=dataclasses.replace(sc.filter, flexure_states=True)), inp)
    assert flex.n_states == 21 and not np.array_equal(flex.outputs[-1].misalignment, e.misalignment)
