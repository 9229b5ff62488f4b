#!/usr/bin/env bash
# Refresh constraints.txt: resolve the project's dependencies afresh in a throw-away venv (Python
# 3.11), then freeze them. Run the full test suite against the new lock before committing it.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="$(mktemp -d)/venv"
python3 -m venv "$venv"
"$venv/bin/pip" install -q torch==2.13.0
"$venv/bin/pip" install -q ".[test,ray,fmi,docs]"
{
  echo "# Every dependency's version as tested (Python 3.11, x86_64, CPU). Used as pip constraints by the"
  echo "# README's commands and .ci/run. Refresh: bash scripts/lock.sh (docs/contributing.md)."
  "$venv/bin/pip" freeze --all --exclude bushenv --exclude pip --exclude wheel \
    | sed 's/^torch==\([0-9.]*\)+cpu/torch==\1/'
} > constraints.txt
rm -rf "$(dirname "$venv")"
echo "constraints.txt refreshed; now, in a fresh venv, the README's test command" >&2
