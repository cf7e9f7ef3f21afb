"""Which ROS domain a run uses (alignment_ros.domain.for_run, behind run_graph.sh and
replay.sh): --domain-id, else an exported ROS_DOMAIN_ID, else a free one; whichever it is,
it is locked, and one another run of this project holds is refused.

A lock is observed as another process would meet it: a second open file description of the
lock file cannot take the exclusive flock the run holds."""
from __future__ import annotations

import fcntl
import subprocess
import sys
from pathlib import Path

import pytest

from alignment_ros import domain


def _locked(dom: int) -> bool:
    with open(domain.LOCK_DIR / f'{dom}.lock', 'w') as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return True
        fcntl.flock(f, fcntl.LOCK_UN)
        return False


@pytest.fixture
def free_domain():
    """A domain no run of this project holds now (claimed, then released: the test claims
    it again through the code under test)."""
    dom = domain.claim()
    domain.release(dom)
    return dom


@pytest.fixture
def claimed():
    """Domains the test's for_run calls claimed, released afterwards."""
    doms: list[int] = []
    yield doms
    for d in doms:
        domain.release(d)


@pytest.mark.parametrize('value', [None, '', '  '])
def test_without_a_domain_given_a_free_one_is_claimed(monkeypatch, claimed, value):
    if value is None:
        monkeypatch.delenv('ROS_DOMAIN_ID', raising=False)
    else:
        monkeypatch.setenv('ROS_DOMAIN_ID', value)    # empty: unset, as rcl reads it
    claimed.append(domain.for_run(None))
    assert claimed[0] in domain.DOMAINS
    assert _locked(claimed[0])


def test_the_exported_domain_is_used_and_locked(monkeypatch, claimed, free_domain):
    monkeypatch.setenv('ROS_DOMAIN_ID', str(free_domain))
    claimed.append(domain.for_run(None))
    assert claimed == [free_domain]
    assert _locked(free_domain)


def test_domain_id_option_wins_over_the_environment(monkeypatch, claimed, free_domain):
    domain.claim(free_domain)
    other = domain.claim()          # another free domain (free_domain is held)
    domain.release(other)
    domain.release(free_domain)
    monkeypatch.setenv('ROS_DOMAIN_ID', str(other))
    claimed.append(domain.for_run(free_domain))
    assert claimed == [free_domain]
    assert not _locked(other)


def test_an_exported_domain_held_by_another_run_is_refused(monkeypatch, free_domain):
    with open(domain.LOCK_DIR / f'{free_domain}.lock', 'w') as other_run:
        fcntl.flock(other_run, fcntl.LOCK_EX | fcntl.LOCK_NB)
        monkeypatch.setenv('ROS_DOMAIN_ID', str(free_domain))
        with pytest.raises(RuntimeError, match=rf'ROS domain {free_domain} is in use.*unset it'):
            domain.for_run(None)
        with pytest.raises(RuntimeError, match=rf'ROS domain {free_domain} is in use'):
            domain.for_run(free_domain)


@pytest.mark.parametrize('value', ['abc', '-1', '233', '4.0', '1e2'])
def test_a_domain_rcl_would_refuse_is_an_error(monkeypatch, value):
    monkeypatch.setenv('ROS_DOMAIN_ID', value)
    with pytest.raises(RuntimeError, match='is not a domain id'):
        domain.for_run(None)


def test_the_processes_of_a_run_keep_its_domain_claimed(free_domain):
    """A launcher hands the lock's descriptor to what it starts (Popen pass_fds): the domain
    stays claimed while any of them lives, even after the launcher let go, and is free once
    the last is gone."""
    import subprocess
    dom = domain.claim(free_domain)
    child = subprocess.Popen(['sleep', '60'], pass_fds=(domain.lock_fd(dom),))
    try:
        domain.release(dom)
        assert _locked(dom)
        child.kill()
        child.wait()
        assert not _locked(dom)
    finally:
        if child.poll() is None:
            child.kill()


_REUSE_PROBE = """
from alignment_ros import domain
first = domain.claim()
domain.release(first)
held = [domain.claim() for _ in range(10)]
for d in held:
    domain.release(d)
fresh = []
while True:                      # hold every domain not yet used until a released one comes back
    d = domain.claim()
    if d == first or d in held:
        break
    fresh.append(d)
print(first, *held)
print(d, *fresh)
"""


def test_a_released_domain_is_claimed_again_last_the_longest_released_first():
    # a participant of this process may still be on a domain it released (rclpy keeps it while
    # a node of it exists): the process takes the domains it has not used first, then the
    # one it released longest ago
    out = subprocess.run([sys.executable, '-c', _REUSE_PROBE], capture_output=True, text=True, check=True)
    first, *held = (int(x) for x in out.stdout.split('\n')[0].split())
    again, *fresh = (int(x) for x in out.stdout.split('\n')[1].split())
    assert first not in held and len(set(held)) == 10
    assert len(fresh) >= 50                         # every unused domain first (all but those other runs hold)
    assert again == first or _locked(first)        # unless another run took it meanwhile


_LINGER_PROBE = """
import gc
import rclpy
from rclpy.context import Context
from alignment_ros import domain
from test_domain import _locked as locked

dom = domain.claim()
ctx = Context()
rclpy.init(context=ctx, domain_id=dom)
node = rclpy.create_node('lingering', context=ctx)
rclpy.try_shutdown(context=ctx)
domain.release(dom)                 # the node, and so its participant, still alive
kept = locked(dom)
node.destroy_node()
del node, ctx
gc.collect()
other = domain.claim()              # a claim lets go what is no longer in use
print(kept, locked(dom), other != dom)
"""


def test_a_domain_is_let_go_only_once_no_participant_of_the_process_is_left_on_it():
    out = subprocess.run([sys.executable, '-c', _LINGER_PROBE], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).parent)            # the probe imports this module's _locked
    assert out.stdout.split() == ['True', 'False', 'True']
