#!/bin/bash
# Splices the COMMANDS section generated from the command table into man/trubal.1.
#   man/update-commands.sh build/trubal
set -eu
exe=${1:-build/trubal}
man=$(dirname "$0")/trubal.1
python3 - "$man" "$("$exe" --man-commands)" <<'PY'
import sys
path, section = sys.argv[1], sys.argv[2]
text = open(path).read()
begin, end = '.\\" BEGIN COMMANDS\n', '.\\" END COMMANDS\n'
a, b = text.index(begin) + len(begin), text.index(end)
open(path, 'w').write(text[:a] + section + ('' if section.endswith('\n') else '\n') + text[b:])
PY
