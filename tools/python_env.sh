#!/usr/bin/env bash
# The project's Python environment: a virtual environment (default .venv/) made from the
# interpreter given (default python3), holding every package pyproject.toml asks for.
#
#   tools/python_env.sh [--python PYTHON] [--venv DIR]
#
# Why a venv: Debian's own python3 is "externally managed" (PEP 668) and refuses `pip install`
# into the system; a venv is the platform's own answer, and works the same on a pyenv or conda
# interpreter. The venv is made once and reused: a second run checks what is installed
# (tools/pydeps.py reads package metadata, no network) and runs pip only for what is missing.
# It is made again when it is broken (its interpreter is gone) or was made from another
# interpreter than the one asked for now.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

python=python3
venv=.venv
while [ $# -gt 0 ]; do
  case "$1" in
    --python) python="$2"; shift ;;
    --venv) venv="$2"; shift ;;
    -h|--help) sed -n '2,12p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "python_env: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

if ! base=$("$python" -c 'import sys; print(sys.base_prefix + "|" + sys.version.split()[0])' 2>/dev/null); then
  echo "python_env: no Python interpreter '$python' (install python3, or give PYTHON=...)" >&2
  exit 2
fi
stamp="$venv/.made-from"

if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c '' 2>/dev/null \
   && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$base" ]; then
  :  # reuse
else
  [ -e "$venv" ] && echo "python_env: making $venv again (it was made from another interpreter, or is broken)" >&2
  rm -rf "$venv"
  echo "python_env: making the virtual environment $venv from $python (${base#*|})" >&2
  if ! "$python" -m venv "$venv"; then
    rm -rf "$venv"
    echo "python_env: '$python -m venv' failed; on Debian install python3-venv (make deps does)" >&2
    exit 1
  fi
  echo "$base" > "$stamp"
fi

missing=$("$venv/bin/python" tools/pydeps.py --missing)
if [ -n "$missing" ]; then
  echo "python_env: installing into $venv:" $missing >&2
  # shellcheck disable=SC2086  # one requirement per word
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $missing
  still=$("$venv/bin/python" tools/pydeps.py --missing)
  if [ -n "$still" ]; then
    echo "python_env: still missing after pip install:" $still >&2
    exit 1
  fi
fi
