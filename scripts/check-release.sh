#!/usr/bin/env bash
# The release check CI runs after the suite: build the sdist and the wheel, check both with
# twine, install the wheel into a fresh venv and run it, and run the unit tests from the
# unpacked sdist on this interpreter (python3) and on every other from 3.10 to 3.13 that this
# machine has. Sourced, it defines its functions and does nothing (tests/unit/test_release.py).

# pip -q still warns of each index folder this machine's pip config names and lacks
quiet_pip() { "$@" 2> >(grep -v "is ignored: it is neither a file nor a directory" >&2); }

# An interpreter that runs, by name on PATH, else pyenv's, else Debian's; pyenv's shims of a
# version that is not selected print an error instead of running, hence the -c check.
find_python() {
    local v=$1 candidate
    for candidate in "$(command -v "python$v" || true)" \
        "$(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$v".*/bin/"python$v" 2>/dev/null | sort -V | tail -1)" \
        "/usr/bin/python$v"; do
        if [ -n "$candidate" ] && "$candidate" -c 'import ensurepip, venv' 2>/dev/null; then
            echo "$candidate"
            return
        fi
    done
}

# The interpreters the sdist's unit tests run on, a line each: "VERSION PATH", or "VERSION"
# alone for one not found. This one (python3) comes first, always: the whole suite ran on it
# from the clone, not from the sdist, and where no other was found a broken sdist passed.
sdist_pythons() {
    local default v
    default=$(python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])')
    echo "$default $(command -v python3)"
    for v in 3.10 3.11 3.12 3.13; do
        [ "$v" = "$default" ] && continue
        echo "$v $(find_python "$v")"
    done
}

[ "${BASH_SOURCE[0]}" = "$0" ] || return 0

set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

python3 -m venv "$work/tools"
quiet_pip "$work/tools/bin/pip" install -q build twine
# build makes the sdist, then the wheel from the unpacked sdist: a file the sdist lacks fails
"$work/tools/bin/python" -m build --outdir "$work/dist" . >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
# setuptools says "SetuptoolsDeprecationWarning" for a deprecated way of declaring things
grep -E "Warning|[Dd]eprecat" "$work/build.log" && { echo "the build warns"; exit 1; }
"$work/tools/bin/twine" check --strict "$work"/dist/*
ls -l "$work"/dist

python3 -m venv "$work/app"
quiet_pip "$work/app/bin/pip" install -q "$work"/dist/*.whl
(cd "$work" && "$work/app/bin/rostools" --version && "$work/app/bin/rostools" demo >/dev/null)
echo "the wheel installs and runs its demo"

mkdir "$work/src"
tar -xzf "$work"/dist/*.tar.gz -C "$work/src"
src=$(echo "$work"/src/*)
corpus=${ROSTOOLS_CORPUS:-$(cd .. && pwd)/shared/corpus}

ran=() missing=()
while read -r v py <&3; do  # fd 3: what the loop runs may read stdin
    if [ -z "$py" ]; then
        echo "Python $v: not found on this machine, its unit tests skipped"
        missing+=("$v")
        continue
    fi
    "$py" -m venv "$work/py$v"
    quiet_pip "$work/py$v/bin/pip" install -q "$src[test]"
    echo "Python $v ($("$py" -c 'import platform; print(platform.python_version())')): unit tests from the sdist"
    # ruff and mypy check the source once, in the main run; here the code runs. The corpus
    # lives beside the clone, not in the sdist.
    if ! (cd "$src" && ROSTOOLS_CORPUS="$corpus" "$work/py$v/bin/python" -m pytest -q \
        -p no:cacheprovider -n 2 tests/unit --ignore=tests/unit/test_quality.py >"$work/unit.log" 2>&1); then
        tail -40 "$work/unit.log"
        echo "Python $v: unit tests failed"
        exit 1
    fi
    tail -1 "$work/unit.log"
    ran+=("$v")
done 3< <(sdist_pythons)
echo "unit tests from the sdist ran on Python ${ran[*]}; not found: ${missing[*]:-none}"
