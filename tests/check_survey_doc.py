#!/usr/bin/env python3
"""Every number docs/survey.md quotes must be in a committed output it cites (issue 24).

Reads files only; it does not rerun the study. The outputs: docs/survey/full.txt (the default
run), docs/survey/quick.json (the CI run), docs/survey/seeds/*/ (scripts/survey-seeds: seedK.txt,
seedK.json, summary.md), robots/er20/survey_published.json (the survey's numbers),
robots/er20/robot.json (the set values), docs/performance.md and docs/accuracy.md (benchmark and
real-log figures with their commands). A decimal number in the document (a token with a decimal point or an exponent; integers
are counts, equation, table and seed numbers) is found when an output holds a value that rounds to
it at the precision quoted: "0.107" matches anything in [0.1065, 0.1075]; signs are ignored.
Section numbers ("Sec. 6.1") are not quantities. A line may carry `<!-- unchecked: REASON -->` when
its numbers are not outputs of the study (inputs and settings, earlier versions' figures kept as
history, arithmetic on quoted numbers); the reason is required and the count of such lines is
printed. Code spans and link targets are skipped. Exit 1 with every unmatched number listed.
What it does not do: tie a number to its cell. It catches a number that appears in no output
(stale after a rerun, invented, copied from another seed); a number changed by a few units in its
last digit still finds some other value of the ~20 000 in the outputs most of the time (measured
on this page: 13 % of such changes caught).
Usage: check_survey_doc.py [PROJECT_DIR]
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


def half_step(token):
    """Half the last quoted digit's place: the rounding tolerance of the quoted number."""
    mantissa, _, exponent = token.lower().partition('e')
    decimals = len(mantissa.split('.')[1]) if '.' in mantissa else 0
    return 0.5 * 10.0 ** ((int(exponent) if exponent else 0) - decimals)


def found(values, token):
    q, h = abs(float(token)), half_step(token) * (1 + 1e-9)
    i = bisect.bisect_left(values, q - h)
    return i < len(values) and values[i] <= q + h


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    doc_path = os.path.join(root, 'docs', 'survey.md')
    outputs = [os.path.join(root, p) for p in ('docs/survey/full.txt', 'docs/survey/quick.json',
                                               'robots/er20/survey_published.json', 'robots/er20/robot.json',
                                               'docs/performance.md', 'docs/accuracy.md')]
    for pattern in ('seed*.txt', 'seed*.json', 'summary.md'):
        outputs += sorted(glob.glob(os.path.join(root, 'docs', 'survey', 'seeds', '*', pattern)))
    missing = [p for p in outputs if not os.path.isfile(p)]
    if missing:
        print('missing outputs: ' + ', '.join(missing))
        return 1
    values = output_values(outputs)
    with open(doc_path, encoding='utf-8') as f:
        lines = f.read().split('\n')
    unmatched, checked, exempt = [], 0, 0
    for number, line in enumerate(lines, 1):
        if UNCHECKED.search(line):
            exempt += 1
            continue
        if '<!--' in line and 'unchecked' in line:
            unmatched.append((number, '(marker)', 'an unchecked marker needs a reason'))
            continue
        body = re.sub(r'`[^`]*`', ' ', line)
        body = re.sub(r'\]\([^)]*\)', ']', body)
        for m in NUMBER.finditer(body):
            token = m.group().lstrip('+-')
            if '.' not in token and 'e' not in token.lower():
                continue
            if re.search(r'(Sec\.|Section|Fig\.|Table) ?$', body[max(0, m.start() - 8):m.start()]):
                continue
            checked += 1
            if not found(values, token):
                unmatched.append((number, token, body[max(0, m.start() - 40):m.end() + 20].strip()))
    print(f'docs/survey.md: {checked} quoted numbers checked against {len(outputs)} committed outputs; '
          f'{exempt} lines marked unchecked')
    for number, token, context in unmatched:
        print(f'  line {number}: {token} not in any output: ...{context}...')
    return 1 if unmatched else 0


if __name__ == '__main__':
    sys.exit(main())
