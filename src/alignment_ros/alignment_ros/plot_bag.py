"""``plot_bag.sh BAG [--out DIR] [--topics TOPIC ...]``: the plots and report.md of any bag of
this project's topics (a run's, a replay's, one imported from a real log): what its topics
allow is drawn (no truth: no error panel; no /ship/odom: no ship motion). BAG is a bag
directory, a lone .mcap, or a run directory holding bag/ (its summary.json then gives the
result table, and a replay's input bag is read too). DIR defaults to the run directory's
plots/ (report.md beside it), else BAG_plots/. Exit status: 0 drawn, 1 nothing to draw, 2 for a
bad command line or a path that is not a bag."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from . import run_report, topics
from .bag import BagError
from .launch import OneLineParser


def parse_args(argv: list[str] | None):
    ap = OneLineParser(prog='plot_bag.sh', description=__doc__)
    ap.add_argument('bag', type=Path, help='bag directory, .mcap file, or run directory')
    ap.add_argument('--out', type=Path, default=None, help='where the PNGs and report.md go')
    ap.add_argument('--topics', nargs='+', default=None, metavar='TOPIC',
                    help='read only these topics (default: every topic the plots use)')
    return ap.parse_args(argv)


def locate(path: Path) -> tuple[Path, Path | None, dict | None, Path | None]:
    """(bag, run directory or None, its summary or None, a replay's input bag or None)."""
    run_dir = path if (path / 'bag').is_dir() else (path.parent if path.name == 'bag' else None)
    bag = run_dir / 'bag' if run_dir is not None else path
    s = None
    if run_dir is not None and (run_dir / 'summary.json').exists():
        s = json.loads((run_dir / 'summary.json').read_text())
    src = Path(s['replayed_from']) if s and s.get('replayed_from') else None
    return bag, run_dir, s, src if src is not None and src.exists() else None


def main(argv: list[str] | None = None) -> int:
    a = parse_args(argv)
    if not a.bag.exists():
        print(f'plot_bag: {a.bag}: no such file or directory', file=sys.stderr)
        return 2
    bag, run_dir, s, src = locate(a.bag)
    unknown = [t for t in a.topics or () if t not in topics.TOPIC_TYPES]
    if unknown:
        print(f"plot_bag: not one of the project's topics: {', '.join(unknown)}", file=sys.stderr)
        return 2
    out = a.out or (run_dir / 'plots' if run_dir is not None else Path(f'{bag}_plots'))
    try:
        report = run_report.build([bag, src], out, s, f'Bag {bag}', a.topics,
                                  report_dir=run_dir if a.out is None and run_dir is not None else out)
    except BagError as e:
        print(f'plot_bag: {e}', file=sys.stderr)
        return 2
    pngs = sorted(out.glob('*.png'))
    if not pngs:
        print(f'plot_bag: {bag}: none of its topics is one the plots draw', file=sys.stderr)
        return 1
    for p in pngs:
        print(p)
    print(report)
    return 0


if __name__ == '__main__':
    sys.exit(main())
