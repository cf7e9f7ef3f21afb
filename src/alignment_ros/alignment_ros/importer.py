"""Import a recorded log (IMU, master INS, and LDV or Doppler radar when given) into a bag of
the project's topics, as a run of the graph records them: /clock (at every stamp),
/master/odom, /master/fix, /aircraft/imu, /ldv/twist, /doppler/twist, in the message layout
the nodes publish (alignment_ros.convert). scripts/replay.sh and scripts/play.sh take it like
a recorded run.

The conversion is alignment_core.recorded's (the canonical CSV layout, or the one a --map
YAML file describes; docs/own-data.md). The bag's metadata (custom_data) records what the
replay needs and a reader should know: the world origin, the time offset added to the log's
times, the IMU rate, whether the master body rate was derived.

Exit status: 0 written; 2 for a bad command line or a log that cannot be read as its layout
says (one message naming the file, column or lines).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import yaml
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock

from alignment_core.recorded import derive, recording
from alignment_core.recorded.column_units import LogError
from alignment_core.units import DEG

from . import convert, topics
from .bag_metadata import BagError
from .bag_writer import BagWriter
from .launch import OneLineParser

META = 'import.'    # custom_data keys of an imported bag
ORIGIN_LAT, ORIGIN_LON = META + 'origin_lat_deg', META + 'origin_lon_deg'
IMU_RATE = META + 'imu_rate_hz'
TIME_OFFSET = META + 'time_offset_ns'


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = OneLineParser(prog='import_log.sh', description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--imu', type=Path, required=True, help='the slave IMU log (.csv or .mat)')
    ap.add_argument('--master', type=Path, required=True, help='the master INS log (.csv or .mat)')
    ap.add_argument('--ldv', type=Path, default=None, help='the LDV log (relative velocity, ship axes)')
    ap.add_argument('--doppler', type=Path, default=None, help='the Doppler radar log (aircraft axes)')
    ap.add_argument('--map', type=Path, default=None, help='a YAML file describing the layout '
                    '(default: the canonical CSV layout)')
    ap.add_argument('--origin', type=str, default=None, metavar='LAT_DEG,LON_DEG',
                    help='the world origin (default: the first master fix)')
    ap.add_argument('--out', type=Path, required=True, help='the bag directory to write (must not exist)')
    return ap.parse_args(argv)


def _origin(text: str | None, log: recording.RecordedLog) -> tuple[float, float]:
    if text is None:
        return recording.origin_of(log)
    try:
        lat, lon = (float(x) for x in text.split(','))
    except ValueError:
        raise LogError(f'--origin: expected LAT_DEG,LON_DEG, got {text!r}') from None
    if not (abs(lat) <= 90.0 and math.isfinite(lon)):
        raise LogError(f'--origin: latitude {lat} out of [-90, 90]')
    return lat * DEG, lon * DEG


def write_bag(log: recording.RecordedLog, origin: tuple[float, float], out: Path,
              sources: dict[str, str]) -> dict[str, int]:
    """Write the bag; return the message count per topic."""
    plane = recording.plane_at(origin)
    custom = {ORIGIN_LAT: repr(math.degrees(origin[0])), ORIGIN_LON: repr(math.degrees(origin[1])),
              TIME_OFFSET: str(log.time_offset_ns), IMU_RATE: repr(derive.rate_hz_of(log.imu.t_ns)),
              META + 'master_body_rate': 'derived from attitude differences' if log.master.rate_derived
              else 'from the log',
              **{META + k + '_log': v for k, v in sources.items()}}
    for name, st in (('imu', log.imu), ('master', log.master), ('ldv', log.ldv), ('doppler', log.doppler)):
        if st is not None:
            custom[f'{META}{name}_rows'] = str(st.report.rows)
            custom[f'{META}{name}_rows_skipped_nan'] = str(st.report.skipped)
    with BagWriter(out, custom_data=custom) as w:
        for t in (topics.CLOCK, topics.MASTER_ODOM, topics.MASTER_FIX, topics.AIRCRAFT_IMU):
            w.add_topic(t, topics.TOPIC_TYPES[t])
        for t_ns in recording.stamps_ns(log):
            w.write(topics.CLOCK, serialize_message(Clock(clock=convert.stamp(int(t_ns)))), int(t_ns))
        for master in recording.master_samples(log, plane):
            w.write(topics.MASTER_ODOM, serialize_message(convert.master_to_msg(master)), master.t_ns)
        m = log.master
        for k, t_ns in enumerate(m.t_ns):
            fix = convert.navsatfix(int(t_ns), topics.FRAME_SHIP, m.lat[k], m.lon[k], m.h[k])
            w.write(topics.MASTER_FIX, serialize_message(fix), int(t_ns))
        for imu in recording.imu_samples(log):       # covariances 0: unknown (REP-145)
            w.write(topics.AIRCRAFT_IMU, serialize_message(convert.imu_to_msg(imu, 0.0, 0.0)), imu.t_ns)
        if log.ldv is not None:
            w.add_topic(topics.LDV_TWIST, topics.TOPIC_TYPES[topics.LDV_TWIST])
            for ldv in recording.ldv_samples(log.ldv):
                w.write(topics.LDV_TWIST, serialize_message(convert.ldv_to_msg(ldv)), ldv.t_ns)
        if log.doppler is not None:
            w.add_topic(topics.DOPPLER_TWIST, topics.TOPIC_TYPES[topics.DOPPLER_TWIST])
            for d in recording.doppler_samples(log.doppler):
                w.write(topics.DOPPLER_TWIST, serialize_message(convert.doppler_to_msg(d)), d.t_ns)
        counts = dict(w.counts)
    return counts


def main(argv: list[str] | None = None) -> int:
    a = parse_args(argv)
    try:
        doc = None
        if a.map is not None:
            if not a.map.exists():
                raise LogError(f'{a.map}: no such file')
            doc = yaml.safe_load(a.map.read_text())
            if doc is not None and not isinstance(doc, dict):
                raise LogError(f'{a.map}: expected a mapping of sections (imu, master, ldv, doppler)')
        log = recording.load(a.imu, a.master, a.ldv, a.doppler, doc)
        origin = _origin(a.origin, log)
        if a.out.exists():
            raise LogError(f'{a.out} already exists; choose another --out')
        sources = {k: str(v) for k, v in (('imu', a.imu), ('master', a.master), ('ldv', a.ldv),
                                          ('doppler', a.doppler), ('map', a.map)) if v is not None}
        counts = write_bag(log, origin, a.out, sources)
    except (LogError, BagError, yaml.YAMLError, OSError) as e:
        print(f'import_log: {e}', file=sys.stderr)
        return 2
    for r in log.reports():
        for line in r.lines():
            print(f'import_log: {line}', file=sys.stderr)
    if log.time_offset_ns:
        print(f'import_log: times shifted by {log.time_offset_ns * 1e-9:.9g} s (recorded in the bag '
              f'metadata as {TIME_OFFSET})', file=sys.stderr)
    if log.master.rate_derived:
        print('import_log: master body rate derived from attitude differences', file=sys.stderr)
    print(f'import_log: origin {math.degrees(origin[0]):.9f} deg, {math.degrees(origin[1]):.9f} deg; '
          f'IMU rate {derive.rate_hz_of(log.imu.t_ns):.6g} Hz', file=sys.stderr)
    print(f'wrote {a.out}: ' + ', '.join(f'{t} {n}' for t, n in counts.items()))
    return 0


if __name__ == '__main__':
    sys.exit(main())
