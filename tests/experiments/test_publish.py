"""The results pipeline (alignment_experiments/publish.py): digests that catch stale numbers,
README blocks replaced between their markers, the compact table taken from a report."""
import pytest

from alignment_experiments import publish

REPORT = """# title

## Results per cell

intro

| filter | RMS r/p/y | p95 r/p/y | mean 1σ r/p/y | in 2σ | NEES [95 %] | mean NIS | settle (s) |
|---|---|---|---|---|---|---|---|
| kf | 0.1/0.2/0.3 | 0.2/0.3/0.4 | 0.1/0.2/0.3 | 0.95/0.95/0.95 | 3.00 [2.36, 3.72] | 3.01 | 1/2/3 |

## Plots
"""


def test_a_perturbed_digest_is_stale(tmp_path):
    runs = tmp_path / 'runs.csv'
    runs.write_text('run,cell\n0,a\n')
    good = publish.digest(runs, 'sha256')
    md = tmp_path / 'results.md'
    md.write_text(f'text\n<!-- quick-digest exp sha256={good} -->\n')
    publish.check_fresh('exp', runs, md)                     # the published numbers: fresh
    bad = ('0' if good[0] != '0' else '1') + good[1:]
    md.write_text(f'text\n<!-- quick-digest exp sha256={bad} -->\n')
    with pytest.raises(publish.StaleResultsError, match='results are stale: run scripts/results.sh'):
        publish.check_fresh('exp', runs, md)
    runs.write_text('run,cell\n0,b\n')                        # the code moved a number
    md.write_text(f'text\n<!-- quick-digest exp sha256={good} -->\n')
    with pytest.raises(publish.StaleResultsError):
        publish.check_fresh('exp', runs, md)
    with pytest.raises(publish.StaleResultsError, match='records no quick digest'):
        publish.check_fresh('other', runs, md)


def test_readme_blocks_are_replaced_between_their_markers_only():
    text = ('a\n<!-- results:x -->\nold x\n<!-- /results:x -->\nb\n'
            '<!-- results:y -->\nold y\n<!-- /results:y -->\nc\n')
    out = publish.update_readme(text, {'x': 'new x\n'})
    assert out == ('a\n<!-- results:x -->\nnew x\n<!-- /results:x -->\nb\n'
                   '<!-- results:y -->\nold y\n<!-- /results:y -->\nc\n')


def test_compact_table_keeps_the_readers_columns():
    rows = publish.compact_table(REPORT).splitlines()
    assert rows[0] == '| filter | RMS r/p/y | mean 1σ r/p/y | NEES [95 %] |'
    assert rows[2] == '| kf | 0.1/0.2/0.3 | 0.1/0.2/0.3 | 3.00 [2.36, 3.72] |'


def test_published_sections_are_kept_verbatim_by_name():
    md = ('# Results\n\nintro\n\n## First\n\n<a id="one"></a>\nbody 1\n\n### sub\n\nmore\n'
          '<!-- quick-digest one sha256=' + '0' * 64 + ' -->\n\n## Second\n\n<a id="two"></a>\nbody 2\n')
    s = publish.published_sections(md)
    assert list(s) == ['one', 'two']
    assert s['one'].startswith('## First') and '### sub' in s['one'] and 'quick-digest one' in s['one']
    assert s['two'] == '## Second\n\n<a id="two"></a>\nbody 2\n'


def test_the_rounded_digest_ignores_the_last_bits_not_the_sixth_digit(tmp_path):
    """The same code on another CPU moves a float's last bits: the published digest (numbers
    rounded to 6 significant digits) stays; a change in the 6th digit, or of an integer, is stale."""
    runs = tmp_path / 'runs.csv'
    runs.write_text('run,cell,err,updates\n0,"kf, capped",0.12345678901234567,300\n')
    md = tmp_path / 'results.md'
    md.write_text(f'<!-- quick-digest exp sha256r6={publish.digest(runs)} -->\n')
    runs.write_text('run,cell,err,updates\n0,"kf, capped",0.12345678901234598,300\n')
    publish.check_fresh('exp', runs, md)
    for moved in ('0.12345778901234567,300', '0.12345678901234567,301'):
        runs.write_text(f'run,cell,err,updates\n0,"kf, capped",{moved}\n')
        with pytest.raises(publish.StaleResultsError):
            publish.check_fresh('exp', runs, md)


def test_redigest_replaces_only_the_digest_of_a_kept_section(tmp_path, monkeypatch):
    """--redigest NAME: the quick version is re-run and its rounded digest replaces the exact one;
    the section's text, and every other section, stay as published."""
    old = '0' * 64
    md = tmp_path / 'results.md'
    body_a = f'## A\n\n<a id="a"></a>\ntable a\n<!-- quick-digest a sha256={old} -->\n'
    body_b = f'## B\n\n<a id="b"></a>\ntable b\n<!-- quick-digest b sha256={old} -->\n'
    md.write_text('# Results\n\nintro\n\n' + body_a + '\n' + body_b)
    readme = tmp_path / 'README.md'
    readme.write_text('readme\n')
    out = tmp_path / 'out'

    def fake_run(args):
        quick = out / f'{args[0]}_quick'
        quick.mkdir(parents=True)
        (quick / 'runs.csv').write_text('run,err\n0,0.1234567\n')
    monkeypatch.setattr(publish, 'RESULTS_MD', md)
    monkeypatch.setattr(publish, 'README', readme)
    monkeypatch.setattr(publish, 'OUT_DIR', out)
    monkeypatch.setattr(publish, 'ROOT', tmp_path)
    monkeypatch.setattr(publish, 'experiments', lambda: {'a': object(), 'b': object()})
    monkeypatch.setattr(publish, '_run', fake_run)
    assert publish.main(['--redigest', 'a']) == 0
    text = md.read_text()
    new = publish.digest(out / 'a_quick' / 'runs.csv')
    assert f'<!-- quick-digest a sha256r6={new} -->' in text and 'table a' in text
    assert body_b.strip() in text
    publish.check_fresh('a', out / 'a_quick' / 'runs.csv', md)
