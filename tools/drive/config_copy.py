#!/usr/bin/env python3
"""A controller configuration copied elsewhere, for a tool that must change it without writing to
the user's file (issue 34: sweep.sh once overwrote it; demo.sh --rival):

    config_copy.py SRC DST [--lift-command-limits]

Its paths (robot: at the top level, plan_file: and key_file: in their blocks) are made absolute,
relative to SRC's folder as stride-mpc resolves them, so that DST works from any folder. With
--lift-command-limits, command.max_velocity becomes [5.0, 2.0, 3.0] (sweep.sh's speed sweep).
Line by line, so that the copy keeps the file's comments and layout."""
import json
import os
import re
import sys


def scalar(text):
    """A YAML scalar's text: quoted, or plain up to a comment."""
    text = text.strip()
    if text[:1] == '"':
        m = re.match(r'"((?:[^"\\]|\\.)*)"', text)
        return json.loads('"%s"' % m.group(1)) if m else None
    if text[:1] == "'":
        m = re.match(r"'((?:[^']|'')*)'", text)
        return m.group(1).replace("''", "'") if m else None
    return re.split(r'\s+#', text)[0].strip()


def main(argv):
    if len(argv) not in (3, 4) or (len(argv) == 4 and argv[3] != '--lift-command-limits'):
        sys.exit('usage: config_copy.py SRC DST [--lift-command-limits]')
    src, dst, lift = argv[1], argv[2], len(argv) == 4
    base = os.path.dirname(os.path.abspath(src))
    out, lifted, command_at = [], False, None
    for line in open(src).read().splitlines():
        m = re.match(r'^(\s*)(robot|plan_file|key_file):(.*)$', line)
        if m and (m.group(2) == 'robot') == (m.group(1) == ''):
            v = scalar(m.group(3))
            if v and not v.startswith('/') and not v.startswith('package://'):
                line = '%s%s: %s' % (m.group(1), m.group(2),
                                     json.dumps(os.path.normpath(os.path.join(base, v))))
        m = re.match(r'^(\s+)max_velocity:', line)
        if lift and m:
            line, lifted = m.group(1) + 'max_velocity: [5.0, 2.0, 3.0]', True
        if re.match(r'^command:', line):
            command_at = len(out)
        out.append(line)
    if lift and not lifted:
        if command_at is None:
            out.append('command: {max_velocity: [5.0, 2.0, 3.0]}')
        elif re.match(r'^command:\s*(#.*)?$', out[command_at]):
            out.insert(command_at + 1, '  max_velocity: [5.0, 2.0, 3.0]')
        else:
            sys.exit("config_copy.py: cannot lift the command limits of '%s' (a flow-style "
                     "command:)" % src)
    with open(dst, 'w') as f:
        f.write('\n'.join(out) + '\n')


if __name__ == '__main__':
    main(sys.argv)
