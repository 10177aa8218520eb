#!/usr/bin/env python3
"""Every number docs/survey.md quotes must be in the committed output its section cites (issue 24).

Reads files only; it does not rerun the study. The outputs: docs/survey/full.txt (the default
run), docs/survey/quick.json (the CI run), docs/survey/seeds/*/ (scripts/survey-seeds: seedK.txt,
seedK.json, summary.md), robots/er20/survey_published.json (the survey's numbers),
robots/er20/robot.json (the set values), docs/performance.md and docs/accuracy.md (benchmark and
real-log figures with their commands). Each section of the page cites its outputs in a comment on
the line after its heading, `<!-- outputs: survey/full.txt ../robots/er20/survey_published.json -->`
(comma-separated, paths relative to docs/, globs allowed; `FILE#HEADING`: only the blank-line-separated
blocks of text file FILE whose first line starts with HEADING, e.g. one table of survey/full.txt); the same
comment at the end of a line of text adds outputs for that line alone; a `###` section without one cites its `##` section's, and
the document's first lines cite with the same comment before the first `##`. A decimal number in a
section (a token with a decimal point or an exponent; integers are counts, equation, table and seed
numbers) is found when one of the section's outputs holds a value that rounds to it at the precision
quoted: "0.107" matches anything in [0.1065, 0.1075]; signs are ignored. Section numbers ("Sec.
6.1") are not quantities. A line may carry `<!-- unchecked: REASON -->` when its numbers are not
outputs of the study (inputs and settings, earlier versions' figures kept as history, arithmetic on
quoted numbers); the reason is required and the count of such lines is printed. Code spans and link
targets are skipped. Exit 1 with every unmatched number listed, or a section with numbers that
cites nothing, or a citation of a file that does not exist.
What it does not do: tie a number to its cell. It catches a number that appears in none of its
section's outputs (stale after a rerun, invented, copied from another seed or run); a number changed
by a few units in its last digit may still find another value of the cited outputs (`--mutations`
measures how often: the share of such changes caught).
Usage: check_survey_doc.py [PROJECT_DIR] [--mutations]
"""
import bisect
import glob
import json
import os
import re
import sys

NUMBER = re.compile(r'(?<![\w.])[-+]?(?:\d+\.\d+|\d+)(?:e[-+]?\d+)?(?![\w])')
UNCHECKED = re.compile(r'<!--\s*unchecked:\s*(\S[^>]*?)\s*-->')


def output_values(paths):
    values = []

    def text(t):
        for m in NUMBER.finditer(t):
            values.append(abs(float(m.group())))

    def walk(x):
        if isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
        elif isinstance(x, bool):
            pass
        elif isinstance(x, (int, float)):
            values.append(abs(float(x)))
        elif isinstance(x, str):
            text(x)

    for p in paths:
        with open(p, encoding='utf-8') as f:
            content = f.read()
        if p.endswith('.json'):
            walk(json.loads(content))
        else:
            text(content)
    return sorted(set(values))


def block_text(path, heading):
    """The blank-line-separated blocks of text file `path` whose first line starts with `heading`."""
    with open(path, encoding='utf-8') as f:
        blocks = re.split(r'\n\s*\n', f.read())
    return '\n'.join(b for b in blocks if b.lstrip('\n').startswith(heading))


def half_step(token):
    """Half the last quoted digit's place: the rounding tolerance of the quoted number."""
    mantissa, _, exponent = token.lower().partition('e')
    decimals = len(mantissa.split('.')[1]) if '.' in mantissa else 0
    return 0.5 * 10.0 ** ((int(exponent) if exponent else 0) - decimals)


def found(values, token):
    q, h = abs(float(token)), half_step(token) * (1 + 1e-9)
    i = bisect.bisect_left(values, q - h)
    return i < len(values) and values[i] <= q + h


OUTPUTS = re.compile(r'<!--\s*outputs:\s*([^>]*?)\s*-->')


def numbers_of(line):
    """The checked decimal tokens of a line (code spans, link targets and section numbers skipped)."""
    body = re.sub(r'`[^`]*`', ' ', line)
    body = re.sub(r'\]\([^)]*\)', ']', body)
    for m in NUMBER.finditer(body):
        token = m.group().lstrip('+-')
        if '.' not in token and 'e' not in token.lower():
            continue
        if re.search(r'(Sec\.|Section|Fig\.|Table) ?$', body[max(0, m.start() - 8):m.start()]):
            continue
        yield token, body[max(0, m.start() - 40):m.end() + 20].strip()


def sections(root, lines):
    """(line number, line, cited output paths or None, problem or None) for every line of the page."""
    docs = os.path.join(root, 'docs')

    def parse(citation):
        paths, problem = [], None
        for item in (x.strip() for x in citation.split(',')):
            pattern, _, heading = item.partition('#')
            hits = sorted(glob.glob(os.path.normpath(os.path.join(docs, pattern))))
            if not hits:
                problem = f'cites {pattern}, which does not exist'
            elif heading and (len(hits) > 1 or hits[0].endswith('.json') or not block_text(hits[0], heading)):
                problem = f'cites {item}: no block of one text file starts with "{heading}"'
            paths += [h + ('#' + heading if heading else '') for h in hits]
        return paths, problem

    top, current, level2 = None, None, None
    pending = None  # the heading whose citation may follow
    for number, line in enumerate(lines, 1):
        m = OUTPUTS.search(re.sub(r'`[^`]*`', ' ', line))  # a citation shown in a code span is text
        if m and OUTPUTS.sub('', line).strip():  # a line of text citing further outputs: that line only
            paths, problem = parse(m.group(1))
            pending = None
            yield number, OUTPUTS.sub('', line), (current or []) + paths, problem
            continue
        if m:
            paths, problem = parse(m.group(1))
            if pending == '#' or pending is None and top is None and current is None:
                top = current = paths
            elif pending == '##':
                level2 = current = paths
            else:
                current = paths
            pending = None
            yield number, line, current, problem
            continue
        if line.startswith('### '):
            pending, current = '###', level2 if level2 is not None else top
        elif line.startswith('## '):
            pending, current, level2 = '##', top, None
        elif line.startswith('# '):
            pending = '#'
        elif line.strip():
            pending = None
        yield number, line, current, None


def check(root, lines, values_of):
    """Unmatched (line, token, context), checked count, exempt count."""
    unmatched, checked, exempt = [], 0, 0
    for number, line, cited, problem in sections(root, lines):
        if problem:
            unmatched.append((number, '(outputs)', problem))
            continue
        if UNCHECKED.search(line):
            exempt += 1
            continue
        if '<!--' in line and 'unchecked' in line:
            unmatched.append((number, '(marker)', 'an unchecked marker needs a reason'))
            continue
        for token, context in numbers_of(line):
            checked += 1
            if cited is None:
                unmatched.append((number, token, 'its section cites no output (<!-- outputs: ... -->)'))
            elif not any(found(values_of(p), token) for p in cited):
                unmatched.append((number, token, 'not in ' + ', '.join(os.path.relpath(p, root) for p in cited) +
                                  ': ...' + context + '...'))
    return unmatched, checked, exempt


def mutations_caught(root, lines, values_of):
    """Share of quoted numbers whose last digit changed by +-1..3 the check flags (each change alone)."""
    caught = total = 0
    for number, line, cited, problem in sections(root, lines):
        if problem or cited is None or UNCHECKED.search(line):
            continue
        for token, _ in numbers_of(line):
            mantissa, e, exponent = token.partition('e') if 'e' in token else (token, '', '')
            digits = [i for i, ch in enumerate(mantissa) if ch.isdigit()]
            last = digits[-1]
            for delta in (-3, -2, -1, 1, 2, 3):
                d = int(mantissa[last]) + delta
                if d < 0 or d > 9:
                    continue
                changed = mantissa[:last] + str(d) + mantissa[last + 1:] + e + exponent
                if float(changed) == 0:
                    continue
                total += 1
                caught += not any(found(values_of(p), changed) for p in cited)
    return caught, total


def main():
    args = [a for a in sys.argv[1:] if not a.startswith('--')]
    root = args[0] if args else os.path.join(os.path.dirname(__file__), '..')
    doc_path = os.path.join(root, 'docs', 'survey.md')
    cache = {}

    def values_of(cited):
        if cited not in cache:
            path, _, heading = cited.partition('#')
            if heading:
                values = []
                for m in NUMBER.finditer(block_text(path, heading)):
                    values.append(abs(float(m.group())))
                cache[cited] = sorted(set(values))
            else:
                cache[cited] = output_values([path])
        return cache[cited]

    with open(doc_path, encoding='utf-8') as f:
        lines = f.read().split('\n')
    unmatched, checked, exempt = check(root, lines, values_of)
    print(f'docs/survey.md: {checked} quoted numbers checked against the outputs their sections cite '
          f'({len(cache)} files); {exempt} lines marked unchecked')
    for number, token, context in unmatched:
        print(f'  line {number}: {token}: {context}')
    if '--mutations' in sys.argv:
        caught, total = mutations_caught(root, lines, values_of)
        print(f'last-digit changes (+-1..3) caught: {caught} of {total} ({100.0 * caught / max(total, 1):.0f} %)')
    return 1 if unmatched else 0


if __name__ == '__main__':
    sys.exit(main())
