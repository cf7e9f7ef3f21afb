"""Run summary from bags: truth vs estimate of the misalignment, 1-sigma, counts, losses.

The mounting misalignment is defined while the aircraft rides the deck (/truth/misalignment
is published only then); the estimate scored is the filter's output at the last such stamp
(the release, or the end of a deck run), or the latest output before it. Only messages stamped
up to the scenario's end are scored (a graph run's run-out after it: alignment_core/run_out.py;
the innovation whiteness is the filter's last report, its run-out's included). A summary says
whether the run is complete (``complete``, ``problems``): a lost message, a foreign one, a run
cut short or anything the launcher saw go wrong makes it incomplete (and the exit non-zero).

The slave INS's own attitude is scored at the same instant (``attitude_*``: the filter's
/alignment/attitude against /truth/aircraft/odom at its stamp, nav-frame rotation vector, its
1-sigma from the published covariance): for a launch from the gear it is the quantity that
matters, what the aircraft carries away (the relative attitude swings by a degree on the struts).

Without truth (a replay of a real recording: no /truth/misalignment in its input), the summary
gives the estimate and its 1-sigma at the filter's last output, truth and error None, and
``truth: false`` (the key is absent otherwise); the table says so.
"""
from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
from rclpy.serialization import deserialize_message
from scipy.spatial.transform import Rotation

from alignment_core.units import ARCMIN

from . import air_data_summary, topics
from .bag import read_bag, stamp_reader, topic_counts
from .bag_topics import BagTopics, topics_of
from .convert import to_ns
from .topics import msg_class

SCORE_KEYS = ('misalignment_truth_rad', 'misalignment_estimate_rad', 'misalignment_sigma_rad',
              'misalignment_error_rad', 'scored_at_s', 'estimate_stamp_s', 'misalignment_valid_s')
ESTIMATE_TOPICS = (topics.ALIGN_MISALIGNMENT, topics.ALIGN_STATE, topics.ALIGN_ATTITUDE, topics.DIAGNOSTICS,
                   *air_data_summary.TOPICS)
"""What the summary reads from the estimate bag, in one pass (bag_topics.py)."""
TRUTH_TOPICS = (topics.TRUTH_MISALIGNMENT,)
"""What it reads from the truth bag (and /truth/aircraft/odom at one stamp, in a pass of its own)."""

Bag = Path | BagTopics
"""A bag's path, or some of its topics already read."""


def _read(bag: Bag, names: tuple[str, ...]) -> dict[str, list]:
    """The messages of each of `names`, deserialised."""
    have = topics_of(bag, names)
    return {n: have.decoded(n) for n in names}


def estimates_from_bag(bag: Bag) -> dict[str, np.ndarray]:
    """t_ns (N,), misalignment (N, 3), sigma (N, 3) from a bag of filter outputs: each
    misalignment with the /alignment/state of the same output, found by the stamp that message
    carries in its first row (it has no header: its place in the bag is when it arrived, and a
    recorder whose reader was matched while outputs already flowed can get one late). An output
    the bag holds only one of the two messages of (a killed recorder) is left out."""
    d = _read(bag, (topics.ALIGN_MISALIGNMENT, topics.ALIGN_STATE))
    sigma_at: dict[float, np.ndarray] = {}
    for m in d[topics.ALIGN_STATE]:
        n = m.layout.dim[1].size
        sigma_at[m.data[0]] = np.asarray(m.data[3 * n:3 * n + 3])
    stamps = [to_ns(m.header.stamp) for m in d[topics.ALIGN_MISALIGNMENT]]
    paired = [(t_ns, m) for t_ns, m in zip(stamps, d[topics.ALIGN_MISALIGNMENT]) if t_ns * 1e-9 in sigma_at]
    t = np.array([t_ns for t_ns, _ in paired], dtype=np.int64)
    mu = np.array([[m.vector.x, m.vector.y, m.vector.z] for _, m in paired])
    sig = np.array([sigma_at[t_ns * 1e-9] for t_ns, _ in paired])
    return {'t_ns': t, 'misalignment': mu.reshape(-1, 3), 'sigma': sig.reshape(-1, 3)}


def state_estimate(bag: Bag, at_s: float | None = None) -> dict | None:
    """The whole estimate from /alignment/state (convert.state_msg): the last message at or
    before `at_s` (the scored instant; None: the last one), as {t_s, labels (with their SI unit),
    estimate, sigma}; None without one (or in the older 4-row layout, which has no estimate)."""
    best = None
    for m in _read(bag, (topics.ALIGN_STATE,))[topics.ALIGN_STATE]:    # by stamp: no header
        rows, cols = m.layout.dim
        n = cols.size
        if rows.size < 5 or n == 0:
            continue
        t = float(m.data[0])
        if (at_s is not None and t > at_s + 5e-4) or (best is not None and t <= best[0]):
            continue
        best = (t, cols.label.split(','), list(m.data[n:2 * n]), list(m.data[2 * n:3 * n]))
    if best is None:
        return None
    return dict(zip(('t_s', 'labels', 'estimate', 'sigma'), best))


def whiteness(bag: Bag) -> dict | None:
    """The alignment filter's last /diagnostics: its innovation whiteness window (pass / fail,
    Ljung-Box q, dof, p, the largest lag-1 autocorrelation and the white band; estimation/
    whiteness.py) and where the relative velocity came from; None before a completed window."""
    last = None
    for m in _read(bag, (topics.DIAGNOSTICS,))[topics.DIAGNOSTICS]:
        for st in m.status:
            if st.name == 'alignment_filter':
                last = {kv.key: kv.value for kv in st.values}
    if last is None or 'whiteness' not in last:
        return None
    out: dict = {'result': last['whiteness'], 'relative_velocity': last.get('relative_velocity', 'ldv')}
    for k in ('q', 'p', 'r1_max', 'band'):
        out[k] = float(last[f'whiteness_{k}'])
    for k in ('dof', 'windows', 'windows_failed'):
        out[k] = int(last[f'whiteness_{k}'])
    return out


def whiteness_line(w: dict | None) -> str:
    """One line of the table for the whiteness of the last window."""
    if not w:
        return 'innovation whiteness: no window completed'
    return (f"innovation whiteness: {w['result']} (last window: Ljung-Box p {w['p']:.3g}, lag-1 "
            f"autocorrelation up to {w['r1_max']:.3f} against +-{w['band']:.3f}; {w['windows_failed']} of "
            f"{w['windows']} windows failed); relative velocity: {w['relative_velocity']}")


def truth_from_bag(bag: Bag, until_ns: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Every /truth/misalignment stamped at or before until_ns (if given): stamps (K,) ns and
    vectors (K, 3) rad; ValueError if there is none."""
    d = [m for m in _read(bag, (topics.TRUTH_MISALIGNMENT,))[topics.TRUTH_MISALIGNMENT]
         if until_ns is None or to_ns(m.header.stamp) <= until_ns]
    if not d:
        raise ValueError(f'{_path(bag)}: no {topics.TRUTH_MISALIGNMENT} messages')
    return (np.array([to_ns(m.header.stamp) for m in d], dtype=np.int64),
            np.array([[m.vector.x, m.vector.y, m.vector.z] for m in d]))


def summarise(truth_bag: Bag, estimate_bag: Bag, start_s: float, duration_s: float,
              wall_time_s: float, published: dict[str, int] | None = None,
              foreign_publishers: dict[str, list[str]] | None = None,
              problems: list[str] | None = None, published_known: bool = True,
              truth: bool = True, latency_s: float = 0.0) -> dict:
    """The summary of a run of `duration_s` simulated seconds from `start_s`: the score (None
    when there is nothing to score), counts, losses, foreign messages, and whether the run is
    complete (no message lost or foreign, outputs up to the end, no `problems` the launcher
    saw). The simulated time claimed is the one the filter's outputs reached; published_known
    False: some publishers' counts are missing (more may be lost than `lost` says); `truth`
    False: the input has no truth (the last estimate and its 1-sigma are reported instead);
    latency_s: the master latency the filter is told (its estimates' time of validity). Each
    bag is read in one pass (`ESTIMATE_TOPICS`, `TRUTH_TOPICS`; both for a bag that is both)."""
    same = _path(truth_bag) == _path(estimate_bag)
    estimate_bag = topics_of(estimate_bag, ESTIMATE_TOPICS + (TRUTH_TOPICS if same else ()))
    truth_bag = estimate_bag if same else topics_of(truth_bag, TRUTH_TOPICS)
    end_ns = round((start_s + duration_s) * 1e9)
    until_ns = end_ns + 1000                   # 1 us: the end given as float seconds
    est = estimates_from_bag(estimate_bag)
    last_ns = int(est['t_ns'][-1]) if len(est['t_ns']) else None
    n_kept = int(np.searchsorted(est['t_ns'], until_ns, side='right'))   # a graph run's run-out: not scored
    est = {k: v[:n_kept] for k, v in est.items()}
    problems = list(problems or [])
    air = air_data_summary.score(estimate_bag)
    score = (_score(truth_bag, estimate_bag, est, problems, optional=air is not None, until_ns=until_ns,
                    latency_ns=round(latency_s * 1e9)) if truth
             else _estimate_only(est, problems))
    if truth and score.get('scored_at_s') is not None:
        score.update(_attitude_score(truth_bag, estimate_bag, round(score['scored_at_s'] * 1e9)))
    own = topic_counts(estimate_bag.path)
    counts = own if same else {**topic_counts(truth_bag.path), **own}
    pub = published or {}
    lost = {k: max(0, pub[k] - counts.get(k, 0)) for k in sorted(pub)}
    foreign = {k: n - pub.get(k, 0) for k, n in sorted(own.items()) if pub and n > pub.get(k, 0)}
    reached = duration_s
    if last_ns is None or last_ns < end_ns - 1000:      # 1 us: the end given as float seconds
        reached = 0.0 if last_ns is None else max(0.0, last_ns * 1e-9 - start_s)
        problems.append(f'cut short: the filter outputs reached t = {start_s + reached:.2f} s '
                        f'of {start_s + duration_s:.2f} s')
    lost_total = int(sum(lost.values()))
    if lost_total:
        problems.append(f'{lost_total} messages lost')
    if foreign:
        problems.append(f'{sum(foreign.values())} messages more than the run published')
    for topic, names in sorted((foreign_publishers or {}).items()):
        problems.append(f'foreign publisher on {topic}: {", ".join(names)}')
    return {
        **score,
        **({} if truth else {'truth': False}),     # the key only where there is none
        'state_estimate': state_estimate(estimate_bag, score.get('scored_at_s')),
        'innovation_whiteness': whiteness(estimate_bag),
        'air_data': air,
        'sim_time_s': reached,
        'planned_sim_time_s': duration_s,
        'wall_time_s': wall_time_s,
        'real_time_factor': reached / wall_time_s if wall_time_s > 0 else None,
        'topics': counts,
        'published': pub,
        'lost': lost,
        'lost_total': lost_total,
        'published_known': published_known,
        'foreign': foreign,
        'foreign_total': int(sum(foreign.values())),
        'foreign_publishers': foreign_publishers or {},
        'complete': not problems,
        'problems': problems,
    }


def _held_validity(bag: Bag, since_ns: int, fallback_ns: int) -> int:
    """The time of validity of an estimate held since the output at since_ns: the filter's first
    /diagnostics from then on says it (`misalignment_valid_ns`, its last match's); fallback_ns if
    none does (an older bag) or the one found is later (a new match)."""
    for m in _read(bag, (topics.DIAGNOSTICS,))[topics.DIAGNOSTICS]:
        if to_ns(m.header.stamp) < since_ns:
            continue
        for st in m.status:
            if st.name == 'alignment_filter':
                v = {kv.key: kv.value for kv in st.values}.get('misalignment_valid_ns', '')
                if v.lstrip('-').isdigit() and int(v) <= since_ns:
                    return int(v)
                return fallback_ns
    return fallback_ns


def _score(truth_bag: Bag, estimate_bag: Bag, est: dict[str, np.ndarray], problems: list[str],
           optional: bool = False, until_ns: int | None = None, latency_ns: int = 0) -> dict:
    """The last estimate of deck matching against the truth at its time of validity (its stamp
    less the master latency the filter is told; the relative attitude moves on the gear and a
    flexing deck); an estimate held since an earlier output (the same vector: no match since, e.g.
    a beam that lost its reflector) is valid where its last match was; None and a problem if
    unavailable (`optional`: a run with air data and no
    deck phase has no misalignment to score)."""
    try:
        t_truth, truth = truth_from_bag(truth_bag, until_ns)
    except ValueError as e:
        if not optional:
            problems.append(f'nothing to score: {e}')
        return dict.fromkeys(SCORE_KEYS)
    t_rel = int(t_truth[-1])
    i = int(np.searchsorted(est['t_ns'], t_rel, side='right')) - 1
    if i < 0:
        problems.append('nothing to score: no filter output before the end of deck matching')
        return dict.fromkeys(SCORE_KEYS)
    j = i                                      # a held estimate (no match since) repeats bit for bit
    while j > 0 and np.array_equal(est['misalignment'][j - 1], est['misalignment'][i]):
        j -= 1
    t_valid = int(est['t_ns'][j]) - latency_ns
    if j < i:
        t_valid = _held_validity(estimate_bag, int(est['t_ns'][j]), t_valid)
    k = min(int(np.searchsorted(t_truth, t_valid)), len(t_truth) - 1)
    mu = truth[k]
    return {
        'misalignment_valid_s': t_valid * 1e-9 if j < i else None,     # only for a held estimate
        'misalignment_truth_rad': mu.tolist(),
        'misalignment_estimate_rad': est['misalignment'][i].tolist(),
        'misalignment_sigma_rad': est['sigma'][i].tolist(),
        'misalignment_error_rad': (est['misalignment'][i] - mu).tolist(),
        'scored_at_s': t_rel * 1e-9,
        'estimate_stamp_s': int(est['t_ns'][i]) * 1e-9,
    }


def _path(bag: Bag) -> Path:
    return bag.path if isinstance(bag, BagTopics) else Path(bag)


def _truth_odometry_at(bag: Bag, t_ns: int):
    """The last /truth/aircraft/odom stamped t_ns, or None: the stamps are read from the raw
    bytes (bag.stamp_reader) and only that message is deserialised."""
    found = None
    readers: dict[str, Callable[[bytes], int] | None] = {}      # by type: looked up once
    for m in read_bag(_path(bag), (topics.TRUTH_AIRCRAFT_ODOM,)):
        if m.type_name not in readers:
            readers[m.type_name] = stamp_reader(m.type_name)
        stamp = readers[m.type_name]
        if stamp is not None and stamp(m.data) == t_ns:
            found = m
    return None if found is None else deserialize_message(found.data, msg_class(found.type_name))


def _attitude_score(truth_bag: Bag, estimate_bag: Bag, at_ns: int | None) -> dict:
    """The slave attitude error at the last /alignment/attitude stamped at or before at_ns against
    /truth/aircraft/odom at that stamp (C_est = (I - [phi x]) C_true, nav frame ENU, rad) and its
    1-sigma; {} without the topics or an exact truth stamp (both run on the IMU's clock)."""
    if at_ns is None:
        return {}
    att = [m for m in _read(estimate_bag, (topics.ALIGN_ATTITUDE,))[topics.ALIGN_ATTITUDE]
           if to_ns(m.header.stamp) <= at_ns]
    if not att:
        return {}
    a = att[-1]
    t = to_ns(a.header.stamp)
    truth = _truth_odometry_at(truth_bag, t)
    if truth is None:
        return {}
    q = truth.pose.pose.orientation
    o = a.pose.pose.orientation
    phi = (Rotation.from_quat([q.x, q.y, q.z, q.w]) * Rotation.from_quat([o.x, o.y, o.z, o.w]).inv()).as_rotvec()
    cov = np.asarray(a.pose.covariance, dtype=float).reshape(6, 6)[3:, 3:]
    return {'attitude_error_rad': phi.tolist(), 'attitude_sigma_rad': np.sqrt(np.diag(cov)).tolist(),
            'attitude_stamp_s': t * 1e-9}


def _estimate_only(est: dict[str, np.ndarray], problems: list[str]) -> dict:
    """The filter's last estimate and its 1-sigma (no truth to score them against)."""
    out = dict.fromkeys(SCORE_KEYS)
    if not len(est['t_ns']):
        problems.append('no filter output')
        return out
    out.update(misalignment_estimate_rad=est['misalignment'][-1].tolist(),
               misalignment_sigma_rad=est['sigma'][-1].tolist(),
               estimate_stamp_s=int(est['t_ns'][-1]) * 1e-9)
    return out


def table(s: dict) -> str:
    lines = []
    if s.get('truth') is False and s.get('misalignment_estimate_rad') is not None:
        est, sig = np.array(s['misalignment_estimate_rad']), np.array(s['misalignment_sigma_rad'])
        lines += [f"misalignment at t = {s['estimate_stamp_s']:.2f} s, no truth in the input: estimate "
                  f"and 1 sigma only (aircraft FLU axes, arcmin)",
                  f"{'axis':<10}{'estimate':>10}{'1 sigma':>10}"]
        for k, name in enumerate(('x (roll)', 'y (pitch)', 'z (yaw)')):
            lines.append(f"{name:<10}{est[k] / ARCMIN:>10.3f}{sig[k] / ARCMIN:>10.3f}")
    elif s.get('misalignment_truth_rad') is not None:
        mu, est = np.array(s['misalignment_truth_rad']), np.array(s['misalignment_estimate_rad'])
        sig = np.array(s['misalignment_sigma_rad'])
        head = f"misalignment at t = {s['scored_at_s']:.2f} s"
        if abs(s['estimate_stamp_s'] - s['scored_at_s']) > 5e-4:   # the latest output is older
            head += f", estimate of t = {s['estimate_stamp_s']:.2f} s"
        valid = s.get('misalignment_valid_s')
        if valid is not None:
            head += f", valid at t = {valid:.2f} s (its last match; truth there)"
        lines += [head + ' (aircraft FLU axes, arcmin)',
                  f"{'axis':<10}{'truth':>10}{'estimate':>10}{'error':>10}{'1 sigma':>10}"]
        for k, name in enumerate(('x (roll)', 'y (pitch)', 'z (yaw)')):
            lines.append(f"{name:<10}{mu[k] / ARCMIN:>10.3f}{est[k] / ARCMIN:>10.3f}"
                         f"{(est[k] - mu[k]) / ARCMIN:>10.3f}{sig[k] / ARCMIN:>10.3f}")
    else:
        lines.append('misalignment: nothing to score')
    if s.get('attitude_error_rad') is not None:
        err, sig = np.array(s['attitude_error_rad']), np.array(s['attitude_sigma_rad'])
        lines.append(f"slave attitude error at t = {s['attitude_stamp_s']:.2f} s (nav frame, arcmin): "
                     + ', '.join(f"{n} {err[k] / ARCMIN:.3f} (1 sigma {sig[k] / ARCMIN:.3f})"
                                 for k, n in enumerate(('east', 'north', 'up'))))
    if 'innovation_whiteness' in s:
        lines.append(whiteness_line(s['innovation_whiteness']))
    if s.get('air_data'):
        lines += air_data_summary.table_lines(s['air_data'])
    rtf = s.get('real_time_factor')
    planned = s.get('planned_sim_time_s', s['sim_time_s'])
    lines.append(f"sim time {s['sim_time_s']:.2f} s"
                 + (f" of {planned:.2f} s" if s['sim_time_s'] < planned else '')
                 + f", wall time {s['wall_time_s']:.2f} s"
                 + (f", real-time factor {rtf:.2f}" if rtf else '')
                 + (f", first message {s['startup_s']:.2f} s after the command" if s.get('startup_s') else ''))
    lines.append('messages recorded (lost):')
    foreign = s.get('foreign', {})
    for k, v in sorted(s['topics'].items()):
        lost = s['lost'].get(k)
        lines.append(f"  {k:<28}{v:>8}" + (f"  ({lost})" if lost is not None else '')
                     + (f"  {foreign[k]} foreign" if k in foreign else ''))
    lines.append(f"lost messages: {s['lost_total']}" + (
        '' if s.get('published_known', True) else ' (some published counts unknown: maybe more)'))
    if s.get('foreign_total'):
        lines.append(f"foreign messages: {s['foreign_total']}")
    lines.append('complete: yes' if s.get('complete') else
                 'INCOMPLETE: ' + '; '.join(s.get('problems') or ['unknown']))
    return '\n'.join(lines)


def write(s: dict, out: Path) -> None:
    (Path(out) / 'summary.json').write_text(json.dumps(s, indent=1))


def report(s: dict, out: Path) -> None:
    """Write summary.json into `out` and print the table and where the run is."""
    write(s, out)
    print(table(s))
    print(f'output: {out}')
