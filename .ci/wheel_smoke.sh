#!/usr/bin/env bash
# The wheel installs and runs anywhere: build it, install it (dependencies from the registry or the
# pip cache; no torch) into a fresh venv outside the source tree, then, from an empty temp folder
# with no source tree on the path, run bim-extract on a copied sample IFC and bim-init run on a
# copied sample site.yaml, and check the packaged data files (schemas, default categories, default
# ONNX detector). Fails loudly on the first thing missing.
# usage: .ci/wheel_smoke.sh   (PYTHON=... picks the interpreter that builds the wheel and the venv)
set -euo pipefail
cd "$(dirname "$0")/.."
SRC=$PWD
PYTHON=${PYTHON:-python3}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/bim-init-wheel.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
fail() { echo "wheel_smoke: FAILED: $*" >&2; exit 1; }

# Build from a copy of the files git knows (tracked, or untracked and not ignored): nothing is
# written into the source tree, and nothing ignored there (a venv, build output) gets in.
echo "wheel_smoke: building the wheel in $WORK/dist"
mkdir -p "$WORK/src"
git -C "$SRC" ls-files -z --cached --others --exclude-standard \
  | (cd "$SRC" && xargs -0 cp --parents -P -t "$WORK/src" 2>/dev/null) || fail "copying the source tree"
# Without build isolation first (no download); an interpreter whose setuptools is older than
# pyproject's build-system asks (a bare CI Python) fails that quietly and builds isolated. Should
# both fail, the first one's errors are shown too.
"$PYTHON" -m pip wheel --quiet --no-deps --no-build-isolation "$WORK/src" -w "$WORK/dist" 2>"$WORK/wheel.err" \
  || "$PYTHON" -m pip wheel --quiet --no-deps "$WORK/src" -w "$WORK/dist" \
  || { cat "$WORK/wheel.err" >&2; fail "pip wheel"; }
WHEEL=$(ls "$WORK"/dist/bim_init-*.whl) || fail "no wheel built"
# Whatever the command line needs at run time must be inside the wheel.
"$PYTHON" - "$WHEEL" <<'PY' || fail "files missing from the wheel"
import sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
need = ["bimtools/default_categories.yaml", "initcli/detector/models/default.onnx",
        "initcli/detector/models/default.json", "bimkit/schemas/site_config.schema.json",
        "bimkit/schemas/eval_config.schema.json", "bimkit/schemas/detection_log.schema.json"]
missing = [n for n in need if n not in names]
if missing:
    sys.exit(f"missing: {', '.join(missing)}")
print(f"wheel_smoke: {len(names)} files in the wheel, data files present")
PY

echo "wheel_smoke: installing into a fresh venv"
"$PYTHON" -m venv "$WORK/venv"
VPY=$WORK/venv/bin/python
"$VPY" -m pip install --quiet --no-compile "$WHEEL" || fail "pip install of the wheel"
for extra in torch numba onnxruntime scipy ray; do
  if "$VPY" -c "import $extra" 2>/dev/null; then fail "$extra got installed (it must stay an extra)"; fi
done

RUN=$WORK/run
mkdir -p "$RUN"
cp "$SRC/sample_models/block_a.ifc" "$SRC/sample_models/block_a.site.yaml" "$RUN/"
cd "$RUN"
export PYTHONPATH=  PYTHONNOUSERSITE=1
# The installed package, not the source tree, must be what runs.
"$VPY" - "$SRC" <<'PY' || fail "the installed package is not the one imported"
import sys, pathlib, bimkit, bimtools, initcli
src = pathlib.Path(sys.argv[1]).resolve()
for mod in (bimkit, bimtools, initcli):
    path = pathlib.Path(mod.__file__).resolve()
    if src in path.parents:
        sys.exit(f"{mod.__name__} imported from the source tree: {path}")
from bimtools.ifc.categories import DEFAULT_CATEGORIES
from initcli.detector import DEFAULT_MODEL
for f in (DEFAULT_CATEGORIES, DEFAULT_MODEL):
    if not f.is_file():
        sys.exit(f"missing packaged file {f}")
print("wheel_smoke: installed package imports; default categories and ONNX model present")
PY
"$WORK/venv/bin/bim-extract" block_a.ifc -o block_a_site || fail "bim-extract"
test -s block_a_site/features.csv || fail "bim-extract wrote no features.csv"
"$WORK/venv/bin/bim-init" run --config block_a.site.yaml --out session --start 10.0,11.0,0 --seed 3 --quiet \
  || fail "bim-init run"
test -s session/summary.json || fail "bim-init run wrote no summary.json"
# The session's claim, found again in its log: the unique match (exit 0) or, of several hypotheses
# (exit 3), the one the lidar along the path favours, named in the notes with the same features.
rc=0
"$WORK/venv/bin/bim-init" match session/session.jsonl --site block_a_site --top 12 --json >match.json || rc=$?
case $rc in 0|3) ;; *) fail "bim-init match on the session log: exit $rc" ;; esac
"$VPY" - <<'PY' || fail "bim-init match does not find the session's claim in its log"
import json, re, sys
match, summary = json.load(open("match.json")), json.load(open("session/summary.json"))
if not summary["success"]:
    sys.exit(f"the session did not initialise: {summary['reason']}")
ranks = [1] if match["exit_code"] == 0 else [
    int(m.group(1)) for n in match["notes"] if (m := re.search(r"favours hypothesis (\d+)", n))]
found = [h for h in match["hypotheses"] if h["rank"] in ranks]
ids = lambda xs: [x for x in xs if x]  # outliers are null
if not found or ids(found[0]["matches"]) != ids(summary["matched_ids"]):
    sys.exit(f"{match['verdict']}; notes {match['notes']}; session matched {summary['matched_ids']}")
print(f"wheel_smoke: bim-init match: {match['verdict']}, the session's claim is hypothesis {ranks[0]}")
PY
if "$WORK/venv/bin/bim-init" eval --out eval_out 2>err.txt; then fail "bim-init eval without --config ran"; fi
grep -q -- "--config" err.txt || fail "bim-init eval without --config: $(cat err.txt)"
# The package alone, after a session (the README's size; it depends on the registry's versions,
# so it is reported, not enforced).
SIZE=$(du -sm "$WORK/venv" | cut -f1)
echo "wheel_smoke: the package alone, after a session: $SIZE MB installed (pip --no-compile)"
# Without the [detector] extra the network is one line naming it; with it, the default model loads.
"$VPY" -c "import cv2, numpy; cv2.imwrite('blank.png', numpy.zeros((32, 32, 3), numpy.uint8))"
if "$WORK/venv/bin/bim-init" detector predict default blank.png >/dev/null 2>err.txt; then fail "predict without onnxruntime ran"; fi
grep -q "bim-init\[detector\]" err.txt || fail "predict without onnxruntime: $(cat err.txt)"
"$VPY" -m pip install --quiet --no-compile "$WHEEL[detector]" || fail "pip install of the wheel's [detector] extra"
"$VPY" - <<'PY' || fail "the default ONNX model does not load with the [detector] extra"
import onnxruntime
from initcli.detector import DEFAULT_MODEL
onnxruntime.InferenceSession(str(DEFAULT_MODEL), providers=["CPUExecutionProvider"])
PY
echo "wheel_smoke: OK ($(basename "$WHEEL"))"
