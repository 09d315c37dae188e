#!/usr/bin/env bash
# The hostile-user probe of issue #26, rerunnable: every concrete case of the issue's body that
# can be run against the `amber` CLI (and `xtask reproduce poisson --test-set`), plus a few
# neighbours of them. Inputs are generated into a temporary directory; nothing is downloaded.
#
#   bash fuzz/probe/run.sh [path/to/amber]
#
# Environment: XTASK (default: `xtask` beside amber), PROBE_TIMEOUT (seconds per case, 60),
# PROBE_MEM_KB (address-space cap per case, `ulimit -v`, default 4 GiB: a case that needs more
# aborts on a failed allocation and is counted oom/killed), PROBE_KEEP=1 keeps the temp directory,
# PROBE_ONLY=REGEX runs only the cases whose name matches.
#
# Each case runs as `nice -n 19 /usr/bin/time timeout $PROBE_TIMEOUT CMD` and gets a verdict:
#   clear-error      non-zero exit, no panic, and the message names the culprit (the input file,
#                    or for option-only inputs the option or the limit that was hit)
#   unclear-error    non-zero exit, but the message names neither
#   panic            stderr contains "panicked" or exit 101
#   oom/killed       killed by a signal (an allocation failure aborts: SIGABRT)
#   hang(timeout)    still running after PROBE_TIMEOUT seconds
#   silently-wrong   exit 0 where the case must fail, or a success whose result is wrong
#   ok               a case that must succeed (or may) succeeded and its result checks out
#   refused          a case that must succeed exited non-zero
#   not-run          the command could not be started (exit 126 or 127)
# The script exits 1 when any verdict is other than clear-error or ok, 2 when setup failed.

set -u -o pipefail

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
AMBER=$(realpath "${1:-$REPO/target/release/amber}")
XTASK=${XTASK:-$(dirname "$AMBER")/xtask}
TIMEOUT=${PROBE_TIMEOUT:-60}
MEM_KB=${PROBE_MEM_KB:-4194304}
ONLY=${PROBE_ONLY:-}
MANIFEST=$REPO/datasets/poisson.json
export AMBER_MODELS=$REPO/models
# A user's environment: no backtraces in the messages.
unset RUST_BACKTRACE RUST_LIB_BACKTRACE
export LC_ALL=C.UTF-8 # character-wise cuts of the messages

die() { echo "probe setup: $*" >&2; exit 2; }
[ -x "$AMBER" ] || die "no amber binary at $AMBER (give its path as the first argument)"
[ -x /usr/bin/time ] || die "/usr/bin/time is missing (apt-get install -y time)"
command -v python3 >/dev/null || die "python3 is needed to write the inputs"
command -v timeout >/dev/null || die "timeout (coreutils) is missing"

W=$(mktemp -d "${TMPDIR:-/tmp}/amber-probe.XXXXXX")
if [ "${PROBE_KEEP:-0}" = 1 ]; then
    echo "probe: keeping $W" >&2
else
    trap 'rm -rf "$W"' EXIT
fi
cd "$W" || die "cannot enter $W"
# Run copies, so that a rebuild during the probe does not swap the binary between cases.
mkdir -p bin
cp "$AMBER" bin/amber || die "cannot copy $AMBER"
A=$W/bin/amber
if [ -x "$XTASK" ]; then cp "$XTASK" bin/xtask && XTASK=$W/bin/xtask; fi
RESULTS=$W/results.tsv
: >"$RESULTS"

# ----------------------------------------------------------------------------------------------
# The case runner.
#
#   case NAME EXPECT CULPRIT POST -- CMD...
#
# EXPECT: fail (must exit non-zero), succeed (must exit 0, and POST must pass), either (exit 0 is
# fine if POST passes; a failure must still be a clear error). CULPRIT: an extended regex the
# output must match for an error to count as naming its cause. POST: a shell command run in the
# case's directory after an exit 0 (`-` for none); its status says whether the result is right
# and its first output line becomes the note. It sees the case's files as $OUT (stdout+stderr).
# Commands run from $W (or $CASE_CWD), so the files they name are short relative paths.
# ----------------------------------------------------------------------------------------------
CASE_CWD=
case_() {
    local name=$1 expect=$2 culprit=$3 post=$4
    shift 5 # the 4 arguments and `--`
    if [ -n "$ONLY" ] && ! [[ $name =~ $ONLY ]]; then return; fi
    local d=$W/cases/${name//\//_}
    mkdir -p "$d"
    local cwd=${CASE_CWD:-$W}
    (
        ulimit -v "$MEM_KB"
        cd "$cwd" && exec nice -n 19 /usr/bin/time -f '%e %M' -o "$d/time" timeout "$TIMEOUT" "$@"
    ) >"$d/stdout" 2>"$d/stderr" </dev/null
    local rc=$?
    cat "$d/stderr" "$d/stdout" >"$d/out"
    local secs mb
    secs=$(tail -1 "$d/time" 2>/dev/null | awk '{print $1}')
    mb=$(tail -1 "$d/time" 2>/dev/null | awk '{printf "%.0f", $2 / 1024}')
    local panicked=no names=no note=
    if grep -q panicked "$d/stderr" || [ "$rc" = 101 ]; then panicked=yes; fi
    if [ "$rc" = 0 ]; then names=-; elif grep -Eq -- "$culprit" "$d/out"; then names=yes; fi
    local verdict
    if [ "$rc" = 124 ]; then
        verdict='hang(timeout)'
    elif [ "$rc" = 126 ] || [ "$rc" = 127 ]; then
        verdict=not-run # the command could not be started
    elif [ "$panicked" = yes ]; then
        verdict=panic
    elif [ "$rc" -ge 128 ]; then
        verdict=oom/killed
        note="signal $((rc - 128))"
    elif [ "$rc" = 0 ]; then
        local post_ok=0
        if [ "$post" != - ]; then
            (cd "$d" && OUT=$d/out bash -c "$post") >"$d/post" 2>&1
            post_ok=$?
            note=$(head -1 "$d/post")
        fi
        case $expect in
            fail) verdict=silently-wrong ;;
            *) if [ "$post_ok" = 0 ]; then verdict=ok; else verdict=silently-wrong; fi ;;
        esac
    else
        if [ "$expect" = succeed ]; then
            verdict=refused
        elif [ "$names" = yes ]; then
            verdict=clear-error
        else
            verdict=unclear-error
        fi
    fi
    # The message: the first line of the error, and its root cause when it has one.
    local msg cause
    msg=$(grep -m1 -E '^(Error|error)' "$d/stderr" || true)
    [ -n "$msg" ] || msg=$(grep -m1 -E 'memory allocation|panicked' "$d/stderr" || true)
    [ -n "$msg" ] || msg=$(grep -v -E '^[[:space:]]*$' "$d/stderr" | tail -1)
    cause=$(awk '/^Caused by:/ {c = 1; next} c && NF {last = $0} END {print last}' "$d/stderr" |
        sed -E 's/^[[:space:]]*([0-9]+:)?[[:space:]]*//')
    if [ -n "$cause" ] && [[ $msg != *"$cause"* ]]; then msg="$msg ⟶ $cause"; fi
    if [ -n "$note" ]; then msg="${msg:+$msg; }$note"; fi
    msg=${msg//$'\t'/ }
    msg=${msg:0:220}
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$verdict" "$rc" "${secs:-?}" "${mb:-?}" "$names" "$msg" >>"$RESULTS"
    printf 'probe: %-44s %-15s exit %-3s %6ss %6s MB\n' "$name" "$verdict" "$rc" "${secs:-?}" "${mb:-?}" >&2
}

# Post-conditions (run in the case directory; $W is exported for them).
export W
# The volume of a .json mesh (2D or 3D) is within a relative tolerance of a value.
volume_is() { # FILE EXPECTED RELTOL
    echo "python3 '$W/tools.py' volume '$1' '$2' '$3'"
}
# The output mentions a pattern.
says() { echo "grep -Eq -- '$1' \"\$OUT\" && grep -Em1 -- '$1' \"\$OUT\""; }

# ----------------------------------------------------------------------------------------------
# Inputs.
# ----------------------------------------------------------------------------------------------
cat >"$W/tools.py" <<'PY'
"""Writes and checks the probe's inputs (standard library only)."""
import base64, json, re, struct, sys

def volume(path, expected, tol):
    m = json.load(open(path))
    V, vol = m["vertices"], 0.0
    for e in m["elements"]:
        p = [V[i] for i in e]
        if len(e) == 4:
            u, v, w = ([p[k][i] - p[0][i] for i in range(3)] for k in (1, 2, 3))
            vol += abs(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                       + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6
        else:
            vol += abs((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])) / 2
    err = abs(vol / float(expected) - 1)
    print(f"volume {vol:.6g} for {float(expected):.6g} (relative error {err:.1e})")
    sys.exit(0 if err <= float(tol) else 1)

def cube_stl(path, scale, solids):
    """An ASCII STL of the cube [0, scale]^3: one solid, or one solid per face."""
    V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    F = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5),
         (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    N = [(0, 0, -1), (0, 0, 1), (0, -1, 0), (1, 0, 0), (0, 1, 0), (-1, 0, 0)]
    out = []
    groups = [F] if solids == 1 else [F[2 * k:2 * k + 2] for k in range(6)]
    for g, tris in enumerate(groups):
        out.append(f"solid face{g}")
        for t in tris:
            n = N[F.index(t) // 2]
            out.append(f" facet normal {n[0]} {n[1]} {n[2]}\n  outer loop")
            for i in t:
                out.append("   vertex %g %g %g" % tuple(scale * c for c in V[i]))
            out.append("  endloop\n endfacet")
        out.append(f"endsolid face{g}")
    open(path, "w").write("\n".join(out) + "\n")

def problems(src):
    """Problem files with an empty initial mesh, an empty expert mesh, an empty load, a duplicated
    expert triangle; expert meshes (amber JSON) with duplicated, overlapping, missing and
    out-of-domain triangles."""
    p = json.load(open(src))
    def variant(name, key, value):
        q = dict(p)
        q[key] = value
        json.dump(q, open(name, "w"))
    empty = {"vertices": [], "triangles": []}
    variant("problem-empty-initial-mesh.json", "initial_mesh", empty)
    variant("problem-empty-expert-mesh.json", "mesh", empty)
    variant("problem-empty-load.json", "load", {"means": [], "covariances": [], "weights": []})
    V = [list(v) for v in p["mesh"]["vertices"]]
    T = [list(t) for t in p["mesh"]["triangles"]]
    variant("problem-duplicated-expert-triangle.json", "mesh", {"vertices": V, "triangles": T + [T[0]]})
    def expert(name, V, T):
        json.dump({"dimension": 2, "vertices": V, "elements": T}, open(name, "w"))
    a, b, c = T[0]
    centroid = [(V[a][k] + V[b][k] + V[c][k]) / 3 for k in range(2)]
    expert("expert-ok.json", V, T)
    expert("expert-duplicated.json", V, T + [T[0]])
    expert("expert-overlapping.json", V + [centroid], T + [[a, b, len(V)]])
    expert("expert-missing-half.json", V, T[: len(T) // 2])
    expert("expert-missing-one.json", V, T[:-1])
    n = len(V)
    expert("expert-out-of-domain.json", V + [[2, 2], [3, 2], [2, 3]], T + [[n, n + 1, n + 2]])

def folder_variants(src, dup, overlap):
    """A 2D amber JSON mesh with a duplicated triangle, and with an overlapping one."""
    m = json.load(open(src))
    V, T = m["vertices"], m["elements"]
    json.dump({"dimension": 2, "vertices": V, "elements": T + [T[0]]}, open(dup, "w"))
    a, b, c = T[0]
    centroid = [(V[a][k] + V[b][k] + V[c][k]) / 3 for k in range(2)]
    json.dump({"dimension": 2, "vertices": V + [centroid], "elements": T + [[a, b, len(V)]]}, open(overlap, "w"))

def nas_cut(src, dst, tets):
    """The .nas file cut after its first `tets` CTETRA cards (no ENDDATA); prints the total."""
    lines = open(src).read().splitlines(True)
    total = sum(1 for l in lines if l.startswith("CTETRA"))
    out, seen = [], 0
    for l in lines:
        if l.startswith("CTETRA"):
            if seen == tets:
                break
            seen += 1
        out.append(l)
    open(dst, "w").write("".join(out))
    print(total)

def nas_mid_card(src, dst):
    """The .nas file cut in the middle of its 5th CTETRA card."""
    text = open(src).read()
    at = [m.start() for m in re.finditer("CTETRA", text)][4]
    open(dst, "w").write(text[: at + 14])

def vtu_variants(ascii_src, binary_src):
    """`size` arrays: ASCII with a non-number, ASCII short, ASCII tiny (1e-6), binary with bad
    base64, binary short (consistent header), binary whose header announces more bytes."""
    s = open(ascii_src).read()
    m = re.search(r'(Name="size"[^>]*>)([^<]*)(</DataArray>)', s)
    vals = m.group(2).split()
    put = lambda name, body: open(name, "w").write(s[: m.start(2)] + body + s[m.end(2):])
    put("size-ascii-corrupt.vtu", " ".join(["0.26x1"] + vals[1:]))
    put("size-ascii-short.vtu", " ".join(vals[:10]))
    put("size-tiny.vtu", " ".join(["1e-6"] * len(vals)))
    b = open(binary_src).read()
    m = re.search(r'(Name="size"[^>]*format="binary"[^>]*>)([^<]*)(</DataArray>)', b)
    body = m.group(2).strip()
    header, data = body[:12], base64.b64decode(body[12:])  # VTK: header and data encoded apart
    assert struct.unpack("<Q", base64.b64decode(header))[0] == len(data)
    put = lambda name, body: open(name, "w").write(b[: m.start(2)] + body + b[m.end(2):])
    put("size-binary-bad-base64.vtu", body[:16] + "!!!!" + body[20:])
    short = data[:80]
    put("size-binary-short.vtu",
        base64.b64encode(struct.pack("<Q", len(short))).decode() + base64.b64encode(short).decode())
    put("size-binary-header-lies.vtu",
        base64.b64encode(struct.pack("<Q", len(data))).decode() + base64.b64encode(short).decode())

def safetensors_nan(path, tensor):
    """Writes a NaN into the first entry of an F32 tensor of a safetensors file."""
    b = bytearray(open(path, "rb").read())
    n = struct.unpack("<Q", b[:8])[0]
    h = json.loads(b[8:8 + n])
    names = [k for k, v in h.items() if k != "__metadata__" and v["dtype"] == "F32"]
    name = tensor if tensor in names else names[0]
    off = 8 + n + h[name]["data_offsets"][0]
    b[off:off + 4] = struct.pack("<f", float("nan"))
    open(path, "wb").write(b)

def predictor(path, edit):
    q = json.load(open(path))
    if edit == "negative-variance":
        q["normaliser"]["node"]["var"][0] = -1.0
    elif edit == "drop-features":
        q["features"]["node"] = q["features"]["node"][:3]
    json.dump(q, open(path, "w"), indent=1)

def results_fields(path):
    """What #26 asks results.json to carry: a schema version, the amber version, the commit,
    per-problem values and the data's hash. Prints what is missing."""
    r = json.load(open(path))
    text = json.dumps(r)
    missing = [k for k in ("schema", "amber_version") if k not in r]
    if not re.fullmatch(r"[0-9a-f]{40}(-dirty)?", str(r.get("commit", ""))):
        missing.append(f"commit ({r.get('commit')!r})")
    runs = r.get("runs") or [{}]
    if not all(run.get("problems") for run in runs):
        missing.append("per-problem values")
    if not all(run.get("test_data_sha256") for run in runs):
        missing.append("the data's hash")
    names = all(any(k in p for k in ("name", "file", "path", "seed")) for run in runs for p in run.get("problems", []))
    extra = "" if names else "; per-problem entries name no problem"
    print(("missing: " + ", ".join(missing) if missing else "schema, amber version, commit, per-problem values, data hash") + extra)
    sys.exit(1 if missing else 0)

def card_commit(path):
    c = json.load(open(path)).get("commit", "")
    print(f"card commit {c!r}")
    sys.exit(0 if re.fullmatch(r"[0-9a-f]{40}(-dirty)?", c) else 1)

def state(path, key, value):
    s = json.load(open(path))
    s[key] = int(value)
    json.dump(s, open(path, "w"))

def ids_collide(path):
    """Whether a checkpoint state's buffer ids repeat (prints them)."""
    s = json.load(open(path))
    ids = [e["id"] for e in s["protected"] + s["generated"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    print(f"buffer ids repeat: {dup[:6]}" if dup else "buffer ids are distinct")
    sys.exit(0 if dup else 1)

if __name__ == "__main__":
    cmd, *args = sys.argv[1:]
    {"volume": volume, "cube_stl": lambda p, s, n: cube_stl(p, float(s), int(n)), "problems": problems,
     "folder_variants": folder_variants, "nas_cut": lambda s, d, t: nas_cut(s, d, int(t)),
     "nas_mid_card": nas_mid_card, "vtu_variants": vtu_variants, "safetensors_nan": safetensors_nan,
     "predictor": predictor, "state": state, "ids_collide": ids_collide,
     "results_fields": results_fields, "card_commit": card_commit}[cmd](*args)
PY
T() { python3 "$W/tools.py" "$@"; }
setup() { # a setup step must succeed
    "$@" >>"$W/setup.log" 2>&1 || { tail -20 "$W/setup.log" >&2; die "failed: $*"; }
}
echo "probe: amber $("$A" --version 2>/dev/null | awk '{print $2}') at $A; work directory $W" >&2

# A smoke Poisson model to corrupt (seconds), and its problems.
setup nice -n 19 "$A" train --profile smoke --steps 5 --difficulty easy --data data --manifest "$MANIFEST" --out smoke
COMMIT=$(python3 -c "import json; print(json.load(open('smoke/model/card.json'))['commit'])" 2>/dev/null || echo unknown)
PROBLEM=data/easy/val/001.json
[ -f "$PROBLEM" ] || die "the smoke training wrote no $PROBLEM"
setup T problems "$PROBLEM"

# Polygons.
echo '{"outer":[[0,0],[1e200,0],[1e200,1e200],[0,1e200]]}' >domain-1e200.json
echo '{"outer":[[0,0],[1e300,0],[1e300,1e300],[0,1e300]]}' >domain-1e300.json
echo '{"outer":[[0,0],[1e149,0],[1e149,1e149],[0,1e149]]}' >domain-1e149.json
echo '{"outer":[[0,0],[1e-300,0],[1e-300,1e-300],[0,1e-300]]}' >domain-1e-300.json
echo '{"outer":[[0,0],[1,0],[1,1],[0,1]]}' >unit.json
echo '{"outer":[[0,0],[1,0],[1,1],[0,1]],"holes":[[[0.1,0.1],[0.9,0.1],[0.9,0.9],[0.1,0.9]],[[0.3,0.3],[0.7,0.3],[0.7,0.7],[0.3,0.7]]]}' >nested-holes.json
echo '{"outer":[[0,0],[1,0],[1,1],[0,1]],"holes":[[[2,2],[3,2],[3,3],[2,3]]]}' >hole-outside.json
echo '{"outer":[[0,0],[1,1],[1,0],[0,1]]}' >bowtie.json
echo '{"outer":[[0,0],[1,0],[1,0.00174533]]}' >needle.json # a 0.1° corner
echo '{"dimension":2,"vertices":[],"elements":[]}' >empty-mesh.json
cat >empty-mesh.vtu <<'EOF'
<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<UnstructuredGrid>
<Piece NumberOfPoints="0" NumberOfCells="0">
<Points><DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii"></DataArray></Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii"></DataArray>
<DataArray type="Int64" Name="offsets" format="ascii"></DataArray>
<DataArray type="UInt8" Name="types" format="ascii"></DataArray>
</Cells>
</Piece>
</UnstructuredGrid>
</VTKFile>
EOF
# Headers claiming huge counts (as in fuzz/corpus).
printf '# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 999999999999 double\n0 0 0\n' >huge-points.vtk
printf '$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 18446744073709551615 1 18446744073709551615\n' >huge-nodes.msh
python3 -c "import struct,sys; sys.stdout.buffer.write(b'\0'*80 + struct.pack('<I', 0xffffffff) + b'\0'*50)" >huge-facets.stl

# Sizing-field meshes: the unit square meshed at 0.25, as binary and ASCII .vtu with a `size` array.
setup "$A" mesh square --size 0.25 -o square.vtu
setup "$A" convert square.vtu square-ascii.vtu --ascii
setup T vtu_variants square-ascii.vtu square.vtu

# Cubes: ASCII STL (one solid; one solid per face), and a tet mesh of the cube as .nas, cut.
setup T cube_stl cube.stl 1 1
setup T cube_stl cube50.stl 50 1
setup T cube_stl cube50-6-solids.stl 50 6
setup "$A" mesh cube.stl --size 0.3 -o cube.nas
setup "$A" mesh cube.stl --size 0.5 -o cube-coarse.nas
NAS_TETS=$(T nas_cut cube.nas cut-12-tets.nas 12)
setup T nas_mid_card cube.nas cut-mid-card.nas

# Folder datasets: 3D with a truncated .nas in train/; 2D with a duplicated or overlapping triangle.
mkdir -p fold3d/train fold3d/val
cp cube.nas fold3d/train/a.nas && cp cut-12-tets.nas fold3d/train/b.nas && cp cube-coarse.nas fold3d/val/c.nas
mkdir -p fold2d/train fold2d/val
setup "$A" mesh square --size 0.2 -o fold2d/train/a.json
setup "$A" mesh lshape --size 0.15 -o fold2d/train/b.json
setup "$A" mesh square --size 0.25 -o fold2d/val/c.json
setup T folder_variants fold2d/train/a.json duplicated-triangle.json overlapping-triangle.json
for defect in duplicated overlapping; do
    mkdir -p "fold2d-$defect/train" "fold2d-$defect/val" "experts-$defect"
    cp "$defect-triangle.json" "fold2d-$defect/train/a.json"
    cp fold2d/train/b.json "fold2d-$defect/train/" && cp fold2d/val/c.json "fold2d-$defect/val/"
    cp "$defect-triangle.json" "experts-$defect/"
done
setup nice -n 19 "$A" train --data fold2d --profile smoke --steps 3 --out fold2d-model

# Corrupted copies of the smoke model.
for m in nan-weight negative-variance dropped-features; do cp -r smoke/model "model-$m"; done
setup T safetensors_nan model-nan-weight/model.safetensors node_encoder.weight
setup T predictor model-negative-variance/predictor.json negative-variance
setup T predictor model-dropped-features/predictor.json drop-features

# Training configs.
echo '{"network":{"latent_dim":1000000000}}' >latent-1e9.json
echo '{"network":{"latent_dim":18446744073709551615}}' >latent-u64max.json
echo '{"network":{"latent_dim":4096}}' >latent-4096.json
echo '{"network":{"latent_dim":1024}}' >latent-1024.json
echo '{"network":{"message_passing_steps":1000000000}}' >mp-steps-1e9.json
echo '{"network":{"message_passing_steps":18446744073709551615}}' >mp-steps-u64max.json
echo '{"network":{"message_passing_steps":256}}' >mp-steps-256.json
echo '{"data":{"train_problems":1000000000}}' >train-problems-1e9.json
echo '{"data":{"train_problems":18446744073709551615}}' >train-problems-u64max.json
echo '{"data":{"train_problems":1000000}}' >train-problems-1e6.json

# A run killed with SIGKILL once it has a checkpoint; copies of it with a doctored checkpoint.
KILL_CONFIG='{"steps": 200, "checkpoint_interval": 5, "validation_interval": 0}'
echo "$KILL_CONFIG" >kill-config.json
TRAIN_KILLED=(train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" --config kill-config.json)
kill_after_first_checkpoint() { # CONFIG OUT: trains, and kills the run at its first checkpoint
    nice -n 19 "$A" train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" --config "$1" \
        --out "$2" >"$2.log" 2>&1 &
    local pid=$!
    for _ in $(seq 12000); do
        [ -e "$2/checkpoints/latest" ] && break
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.01
    done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    [ -e "$2/checkpoints/latest" ] || die "the run to kill wrote no checkpoint ($2.log: $(tail -1 "$2.log"))"
    [ -e "$2/model" ] && die "the run to kill finished before it was killed"
}
kill_after_first_checkpoint kill-config.json killed
LATEST=$(cat killed/checkpoints/latest)
for c in latest-relative latest-absolute latest-missing nan-checkpoint planted-temporaries; do
    mkdir -p "ckpt-$c" && cp -r killed "ckpt-$c/run"
done
# Five more kills, 0.25-0.6 s after a resume, to catch writes in progress; what each kill leaves
# is counted before the next resume sweeps it.
KILL_TMPS=$(find killed -name '*.tmp' | wc -l)
KILL_EMPTY_TMPS=$(find killed -name '*.tmp' -size 0 | wc -l)
KILLS=1
for delay in 0.35 0.5 0.25 0.6 0.45; do
    nice -n 19 "$A" "${TRAIN_KILLED[@]}" --out killed >>killed.log 2>&1 &
    pid=$!
    sleep "$delay"
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    [ -e killed/model ] && die "the run to kill finished before it was killed"
    KILLS=$((KILLS + 1))
    KILL_TMPS=$((KILL_TMPS + $(find killed -name '*.tmp' | wc -l)))
    KILL_EMPTY_TMPS=$((KILL_EMPTY_TMPS + $(find killed -name '*.tmp' -size 0 | wc -l)))
done
mkdir -p ckpt-latest-relative/x ckpt-latest-absolute/x
cp -r "ckpt-latest-relative/run/checkpoints/$LATEST" ckpt-latest-relative/x/
cp -r "ckpt-latest-absolute/run/checkpoints/$LATEST" ckpt-latest-absolute/x/
printf '../../x/%s' "$LATEST" >ckpt-latest-relative/run/checkpoints/latest
printf '%s/ckpt-latest-absolute/x/%s' "$W" "$LATEST" >ckpt-latest-absolute/run/checkpoints/latest
printf 'step-99999999' >ckpt-latest-missing/run/checkpoints/latest
# next_entry_id = 2^64-1 in a run of 30 steps: the buffer (20 entries) keeps what the resume adds.
echo '{"steps": 30, "checkpoint_interval": 5, "validation_interval": 0}' >short-kill-config.json
mkdir -p ckpt-next-entry-id
kill_after_first_checkpoint short-kill-config.json ckpt-next-entry-id/run
setup T state "ckpt-next-entry-id/run/checkpoints/$(cat ckpt-next-entry-id/run/checkpoints/latest)/state.json" \
    next_entry_id 18446744073709551615
setup T safetensors_nan "ckpt-nan-checkpoint/run/checkpoints/$LATEST/model.safetensors" x
# Temporaries of writes whose owner is dead, 0 bytes, as a kill leaves them.
sh -c 'exit 0' &
dead=$!
wait "$dead"
for f in run/.training_state.json run/checkpoints/.latest "run/checkpoints/$LATEST/.model.safetensors"; do
    : >"ckpt-planted-temporaries/${f%/*}/${f##*/}.$dead-0.tmp"
done

# `xtask reproduce poisson --test-set DIR`: problem files not named NNN.json; none; a non-problem.
mkdir -p testset-names testset-none testset-foreign
cp "$PROBLEM" testset-names/plate-a.json && cp data/easy/train/seed0/000.json testset-names/b.json
echo 'not a problem' >testset-none/notes.txt
cp "$PROBLEM" testset-foreign/plate-a.json && echo '{"name": "not a problem"}' >testset-foreign/notes.json
echo '{"steps": 5}' >steps-5.json
echo '{"steps": 150, "checkpoint_interval": 1000, "validation_interval": 0}' >repro-config.json
setup env RAYON_NUM_THREADS=2 nice -n 19 "$A" train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" \
    --config repro-config.json --out repro-2
REPRODUCE=(reproduce poisson --profile smoke --difficulty easy --methods amber-mean --seeds 1
    --config "$W/steps-5.json" --data-root "$W/data" --allow-dirty)

# ----------------------------------------------------------------------------------------------
# The cases.
# ----------------------------------------------------------------------------------------------
LIMIT='cap of|--max-elements|--size'

# Unbounded memory: extreme sizes.
case_ size/domain-1e200-size-1e199-cap-100 fail "domain-1e200.json|$LIMIT" - -- \
    "$A" mesh domain-1e200.json --size 1e199 --max-elements 100 -o out.vtu
case_ size/domain-1e300-size-1e299-cap-100 fail "domain-1e300.json|$LIMIT" - -- \
    "$A" mesh domain-1e300.json --size 1e299 --max-elements 100 -o out.vtu
case_ size/domain-1e149-size-1e148-cap-100 fail "domain-1e149.json|$LIMIT" - -- \
    "$A" mesh domain-1e149.json --size 1e148 --max-elements 100 -o out.vtu
# 100 edges a side: a scaled unit square well under the cap, and coordinates inside the ±1e150
# the domains accept; meshing it or refusing it clearly are both fine.
case_ size/domain-1e149-size-1e147 either "domain-1e149.json|$LIMIT" "$(volume_is ../../out-1e149.json 1e298 1e-9)" -- \
    "$A" mesh domain-1e149.json --size 1e147 -o out-1e149.json
case_ size/domain-1e-300-size-1e-301 fail "domain-1e-300.json|$LIMIT" - -- \
    "$A" mesh domain-1e-300.json --size 1e-301 -o out.vtu
case_ size/unit-square-size-1e-5 fail "$LIMIT" - -- "$A" mesh square --size 1e-5 -o out.vtu
case_ size/unit-square-size-1e-4 fail "$LIMIT" - -- "$A" mesh square --size 1e-4 -o out.vtu
case_ size/unit-json-size-1e-5 fail "unit.json|$LIMIT" - -- "$A" mesh unit.json --size 1e-5 -o out.vtu
case_ size/unit-json-size-1e-4 fail "unit.json|$LIMIT" - -- "$A" mesh unit.json --size 1e-4 -o out.vtu
case_ size/unit-square-size-1e-300 fail "$LIMIT" - -- "$A" mesh square --size 1e-300 -o out.vtu
case_ size/unit-square-size-1e-4-cap-100 fail "$LIMIT" - -- "$A" mesh square --size 1e-4 --max-elements 100 -o out.vtu
case_ size/size-mesh-of-1e-6 fail "size-tiny.vtu|$LIMIT" - -- "$A" mesh square --size size-tiny.vtu -o out.vtu
case_ size/cube-stl-size-1e-3 fail "cube.stl|$LIMIT" - -- "$A" mesh cube.stl --size 1e-3 -o out.vtu
# About 8 M tets for a cap of 5 M (the cube at 2e-2 gives 0.97 M in 6 s).
case_ size/cube-stl-size-1e-2 fail "cube.stl|$LIMIT" - -- "$A" mesh cube.stl --size 1e-2 -o out.vtu

# Panics: empty meshes; configs without upper bounds.
case_ empty/problem-initial-mesh fail 'problem-empty-initial-mesh.json' - -- \
    "$A" mesh --model smoke --problem problem-empty-initial-mesh.json -o out.vtu
# The problem's expert mesh is the default --expert: an empty one is a broken file, not "no expert".
case_ empty/problem-expert-mesh fail 'problem-empty-expert-mesh.json' \
    "grep -q 'normalised DCD' \"\$OUT\" || echo 'the empty expert mesh is ignored: no step is scored, no warning'" -- \
    "$A" mesh --model smoke --problem problem-empty-expert-mesh.json -o out.vtu
case_ empty/size-mesh-json fail 'empty-mesh.json' - -- "$A" mesh square --size empty-mesh.json -o out.vtu
case_ empty/size-mesh-vtu fail 'empty-mesh.vtu' - -- "$A" mesh square --size empty-mesh.vtu -o out.vtu
TRAIN=(train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" --steps 5)
for c in latent-1e9 latent-u64max latent-4096 mp-steps-1e9 mp-steps-u64max train-problems-1e9 train-problems-u64max \
    train-problems-1e6; do
    case_ "config/$c" fail "$c.json" - -- "$A" "${TRAIN[@]}" --config "$c.json" --out "run-$c"
done
# The largest values the config checks accept: training runs, or refuses clearly; not an abort.
case_ config/latent-1024-accepted-maximum either 'latent-1024.json' 'test -f ../../run-latent-1024/model/model.safetensors' -- \
    "$A" "${TRAIN[@]}" --config latent-1024.json --out run-latent-1024
case_ config/mp-steps-256-accepted-maximum either 'mp-steps-256.json' 'test -f ../../run-mp-steps-256/model/model.safetensors' -- \
    "$A" "${TRAIN[@]}" --config mp-steps-256.json --out run-mp-steps-256

# Silently wrong: truncated .nas (cut at 12 of $NAS_TETS tets, no ENDDATA).
case_ nas/cut-at-12-tets-convert fail 'cut-12-tets.nas' - -- "$A" convert cut-12-tets.nas out.vtu
case_ nas/cut-at-12-tets-as-geometry fail 'cut-12-tets.nas' - -- "$A" mesh cut-12-tets.nas --size 0.5 -o out.vtu
case_ nas/cut-at-12-tets-in-training-folder fail 'b.nas' - -- \
    "$A" train --data fold3d --profile smoke --steps 2 --out run-fold3d
case_ nas/cut-mid-card-convert fail 'cut-mid-card.nas' - -- "$A" convert cut-mid-card.nas out.vtu

# .vtu `size` arrays, corrupt or short, as --size fields (and converted).
for v in size-ascii-corrupt size-ascii-short size-binary-bad-base64 size-binary-short size-binary-header-lies; do
    case_ "vtu/$v-as-size-field" fail "$v.vtu" - -- "$A" mesh square --size "$v.vtu" -o out.vtu
done
case_ vtu/size-ascii-corrupt-convert fail 'size-ascii-corrupt.vtu' - -- "$A" convert size-ascii-corrupt.vtu out.json
case_ vtu/size-binary-short-convert fail 'size-binary-short.vtu' - -- "$A" convert size-binary-short.vtu out.json

# Expert meshes that do not conform to or cover the domain, given to `amber mesh --expert`.
case_ expert/control-valid-expert succeed 'expert-ok.json' "$(says 'normalised DCD')" -- \
    "$A" mesh --model smoke --problem "$PROBLEM" --expert expert-ok.json -o out.vtu
for e in duplicated overlapping missing-half missing-one out-of-domain; do
    case_ "expert/$e-triangles" fail "expert-$e.json" "$(says '^expert:')" -- \
        "$A" mesh --model smoke --problem "$PROBLEM" --expert "expert-$e.json" -o out.vtu
done
case_ expert/duplicated-triangle-in-problem-file fail 'problem-duplicated-expert-triangle.json' "$(says '^expert:')" -- \
    "$A" mesh --model smoke --problem problem-duplicated-expert-triangle.json -o out.vtu
for defect in duplicated overlapping; do
    case_ "expert/$defect-triangle-in-training-folder" fail 'a.json' - -- \
        "$A" train --data "fold2d-$defect" --profile smoke --steps 2 --out "run-fold2d-$defect"
    case_ "expert/$defect-triangle-in-evaluate-folder" fail "$defect-triangle.json" - -- \
        "$A" evaluate --model fold2d-model --data "experts-$defect" --out "evaluation-$defect"
done

# An empty load mixture.
case_ load/empty-mixture fail 'problem-empty-load.json' "echo 'meshed for a load of no Gaussians'" -- \
    "$A" mesh --model smoke --problem problem-empty-load.json -o out.vtu

# Models: NaN weights, a negative normaliser variance, features that do not fit the network.
case_ model/nan-weight fail 'model.safetensors|model-nan-weight' - -- \
    "$A" mesh --model model-nan-weight --problem "$PROBLEM" -o out.vtu
case_ model/negative-normaliser-variance fail 'predictor.json|model-negative-variance' - -- \
    "$A" mesh --model model-negative-variance --problem "$PROBLEM" -o out.vtu
# The issue's unclear error `graph batch: node features: expected width 3, found 6`.
case_ model/features-not-the-network-width fail 'predictor.json|model.json|model-dropped-features' - -- \
    "$A" mesh --model model-dropped-features --problem "$PROBLEM" -o out.vtu

# Degenerate output (a 0.1° corner): meshing it is fine, with a warning; so is a clear refusal.
case_ mesh/degenerate-output-size-field either 'needle.json' "$(says 'warning: .*degenerate')" -- \
    "$A" mesh needle.json --size 0.1 -o out.vtu
case_ mesh/degenerate-output-model either 'needle.json' "$(says 'warning: .*degenerate')" -- \
    "$A" mesh needle.json --model smoke --problem "$PROBLEM" -o out.vtu

# Polygons: nested holes (an island), a hole outside, a self-intersecting ring.
case_ polygon/nested-holes fail 'nested-holes.json' - -- "$A" mesh nested-holes.json --size 0.1 -o out.vtu
case_ polygon/hole-outside-the-outer-ring fail 'hole-outside.json' - -- "$A" mesh hole-outside.json --size 0.1 -o out.vtu
case_ polygon/self-intersecting fail 'bowtie.json' - -- "$A" mesh bowtie.json --size 0.1 -o out.vtu

# ASCII STL cubes keep their volume (the issue saw 11 %).
case_ stl/ascii-cube-size-field succeed 'cube50.stl' "$(volume_is out.json 125000 1e-6)" -- \
    "$A" mesh cube50.stl --size 10 -o cases/stl_ascii-cube-size-field/out.json
case_ stl/ascii-cube-six-solids-size-field succeed 'cube50-6-solids.stl' "$(volume_is out.json 125000 1e-6)" -- \
    "$A" mesh cube50-6-solids.stl --size 10 -o cases/stl_ascii-cube-six-solids-size-field/out.json
if [ -f "$AMBER_MODELS/console/model.safetensors" ]; then
    case_ stl/ascii-cube-console-model succeed 'cube50.stl' "$(volume_is out.json 125000 1e-6)" -- \
        "$A" mesh cube50.stl --model console --steps 2 -o cases/stl_ascii-cube-console-model/out.json
else
    echo "probe: skipping stl/ascii-cube-console-model: no $AMBER_MODELS/console" >&2
fi

# Headers claiming huge counts.
case_ header/vtk-points-1e12 fail 'huge-points.vtk' - -- "$A" convert huge-points.vtk out.vtu
case_ header/msh-nodes-u64max fail 'huge-nodes.msh' - -- "$A" convert huge-nodes.msh out.vtu
case_ header/stl-facets-u32max fail 'huge-facets.stl' - -- "$A" mesh huge-facets.stl --size 0.3 -o out.vtu

# Trust: checkpoints of a run killed with SIGKILL, resumed by the same command.
for c in latest-relative latest-absolute latest-missing; do
    case_ "checkpoint/$c" fail 'checkpoints/latest|step-99999999' - -- "$A" "${TRAIN_KILLED[@]}" --out "ckpt-$c/run"
done
case_ checkpoint/next-entry-id-u64max fail 'state.json|next_entry_id' \
    "python3 '$W/tools.py' ids_collide \$(ls -d '$W'/ckpt-next-entry-id/run/checkpoints/step-* | tail -1)/state.json" -- \
    "$A" train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" --config short-kill-config.json \
    --out ckpt-next-entry-id/run
case_ checkpoint/nan-weight fail 'model.safetensors' - -- "$A" "${TRAIN_KILLED[@]}" --out ckpt-nan-checkpoint/run
# After a resume, no temporary of a dead writer is left: the planted 0-byte ones, and whatever the
# SIGKILL left ($KILL_TMPS temporaries, $KILL_EMPTY_TMPS of them empty).
LEFT='n=$(find "$1" -name "*.tmp" | wc -l); echo "$n temporaries left"; test "$n" = 0'
case_ checkpoint/planted-dead-temporaries-removed succeed 'tmp' "bash -c '$LEFT' _ '$W/ckpt-planted-temporaries/run'" -- \
    "$A" "${TRAIN_KILLED[@]}" --out ckpt-planted-temporaries/run
case_ checkpoint/kill-9-then-resume succeed 'tmp' "bash -c '$LEFT' _ '$W/killed'" -- \
    "$A" "${TRAIN_KILLED[@]}" --out killed

# `xtask reproduce poisson --test-set DIR` (run from the repository: it reads datasets/).
if [ -x "$XTASK" ]; then
    CASE_CWD=$REPO
    case_ reproduce/test-set-any-file-names succeed 'testset-names' "$(says 'test normalised DCD .*\(2 problems')" -- \
        "$XTASK" "${REPRODUCE[@]}" --test-set "$W/testset-names" --runs "$W/xruns-names" --out "$W/xout-names"
    case_ reproduce/test-set-without-problems fail 'testset-none' - -- \
        "$XTASK" "${REPRODUCE[@]}" --test-set "$W/testset-none" --runs "$W/xruns-none" --out "$W/xout-none"
    case_ reproduce/test-set-with-a-foreign-json fail 'notes.json' - -- \
        "$XTASK" "${REPRODUCE[@]}" --test-set "$W/testset-foreign" --runs "$W/xruns-foreign" --out "$W/xout-foreign"
    CASE_CWD=
else
    echo "probe: skipping the reproduce cases: no xtask at $XTASK (set XTASK)" >&2
fi

# Reproducibility: the same seed and config give the same model bytes, at 2 threads twice and at
# 1 thread (150 smoke steps: the issue saw runs part at step 101). The first run is setup.
REPRO=(train --profile smoke --difficulty easy --data data --manifest "$MANIFEST" --config repro-config.json)
SAME="cmp -s ../../repro-2/model/model.safetensors model.safetensors && cmp -s ../../repro-2/model/predictor.json predictor.json"
case_ repro/same-seed-2-threads-same-bytes succeed 'repro' \
    "cd ../../repro-2b/model && $SAME && echo \"model bytes identical: \$(sha256sum model.safetensors | cut -c1-16)\"" -- \
    env RAYON_NUM_THREADS=2 "$A" "${REPRO[@]}" --out repro-2b
case_ repro/same-seed-1-thread-same-bytes succeed 'repro' \
    "cd ../../repro-1/model && $SAME && echo \"model bytes identical: \$(sha256sum model.safetensors | cut -c1-16)\"" -- \
    env RAYON_NUM_THREADS=1 "$A" "${REPRO[@]}" --out repro-1

# Provenance: the commit comes from the binary (trained outside any checkout), and results.json
# carries what #26 asks of it.
case_ provenance/card-commit-outside-a-checkout succeed 'card' "python3 '$W/tools.py' card_commit ../../prov-run/model/card.json" -- \
    "$A" "${TRAIN[@]}" --out prov-run
if [ -x "$XTASK" ]; then
    CASE_CWD=$REPO
    case_ provenance/results-json-fields succeed 'results' "python3 '$W/tools.py' results_fields '$W/xout-names/results.json'" -- \
        "$XTASK" "${REPRODUCE[@]}" --test-set "$W/testset-names" --runs "$W/xruns-names" --out "$W/xout-names"
    CASE_CWD=
fi

# ----------------------------------------------------------------------------------------------
# The report.
# ----------------------------------------------------------------------------------------------
echo
echo "amber: a copy of \`$AMBER\` ($("$A" --version 2>/dev/null), sha256 $(sha256sum "$A" | cut -c1-12), built from $COMMIT); timeout ${TIMEOUT} s and address space $((MEM_KB / 1024)) MB per case; the truncated .nas is cut at 12 of $NAS_TETS tets; $KILLS SIGKILLs of \`amber train\` left $KILL_TMPS temporaries ($KILL_EMPTY_TMPS empty) before the next resume."
echo
echo '| case | verdict | exit | s | max RSS MB | names culprit | message |'
echo '|---|---|---|---|---|---|---|'
while IFS=$'\t' read -r name verdict rc secs mb names msg; do
    msg=${msg//|/\\|}
    msg=${msg//\`/\'}
    echo "| $name | $verdict | $rc | $secs | $mb | $names | \`$msg\` |"
done <"$RESULTS"
echo
echo '| verdict | cases |'
echo '|---|---|'
cut -f2 "$RESULTS" | sort | uniq -c | sort -rn | awk '{print "| " $2 " | " $1 " |"}'
echo
awk -F'\t' '$1 ~ /^size\// {
        if ($4 + 0 >= t) { t = $4 + 0; tc = $1 }
        if ($5 + 0 >= m) { m = $5 + 0; mc = $1 }
    } END {
        if (tc != "") printf "Extreme sizes (size/*): worst time %s s (%s), worst max RSS %s MB (%s)\n", t, tc, m, mc
    }' "$RESULTS"
total=$(wc -l <"$RESULTS")
bad=$(cut -f2 "$RESULTS" | grep -cv -E '^(clear-error|ok)$')
echo "$total cases, $bad not a clear error or ok"
[ "$bad" = 0 ]
