#!/usr/bin/env bash
# The hostile-input cases of docs/hostile-input.md. Usage:
#   scripts/hostile_cases.sh BIN_DIR SCRATCH_DIR > cases.tsv
# BIN_DIR holds built example binaries (target/release/examples); SCRATCH_DIR is written to.
# Prints one line per case: id, exit status, the last line printed (tab-separated). Each case
# runs under a time limit and a 6 GB address-space limit, so an unbounded allocation aborts.
# ONLY=36 runs only the cases of issue 36 (the entry points added since the first sweep);
# ONLY=56 only those of issue 56 (data loss, panics, hangs, the up axis, tilt, parts left out,
# errors that name their cause).
BIN=$(cd "$1" && pwd); T=$2; mkdir -p "$T"; T=$(cd "$T" && pwd)
cd "$(dirname "$0")/.."
export MIMALLOC_PURGE_DELAY=-1 RUST_BACKTRACE=0
printf '#####\n#S..#\n#.#G#\n#####\n' > $T/grid.txt
cat $T/grid.txt > $T/two.txt; echo >> $T/two.txt; cat $T/grid.txt >> $T/two.txt
head -c 100 /dev/urandom > $T/bad.png; printf '#\n' > $T/wall.txt
python3 -c "
import struct
hdr=b\"{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4), }\"
hdr=hdr+b' '*(118-len(hdr))+b'\\n'
open('$T/float.npy','wb').write(b'\\x93NUMPY\\x01\\x00'+struct.pack('<H',len(hdr))+hdr+b'\\0'*64)"
python3 -c "
rows=['S'+'.'*27]+['.'*28 for _ in range(26)]+['.'*27+'G']
open('$T/pic.txt','w').write('\\n'.join(rows)+'\\n')"
head -c 5000 models/vin_8.safetensors > $T/broken.safetensors
python3 -c "
n=2000
rows=['S'+'.'*(n-1)]+['.'*n for _ in range(n-2)]+['.'*(n-1)+'G']
open('$T/big.txt','w').write('\n'.join(rows)+'\n')"
# runw: as run, but the first warning printed (or, with none, the last line).
runw() { id=$1; shift; lim=$1; shift; out=$( (ulimit -v 6000000; timeout $lim "$@") 2>&1 ); rc=$?; w=$(printf '%s' "$out" | grep -m1 "warning:\|^Error" | cut -c1-150); [ -z "$w" ] && w="no warning: $(printf '%s' "$out" | grep -v '^\s*$' | tail -1 | cut -c1-120)"; printf '%s\t%s\t%s\n' "$id" "$rc" "$w"; }
run() { id=$1; shift; lim=$1; shift; out=$( (ulimit -v 6000000; timeout $lim "$@") 2>&1 ); rc=$?; last=$(printf '%s' "$out" | grep -v '^\s*$' | grep -v "at \./\|^ *[0-9]*: \|^stack backtrace\|note: run with" | tail -1 | cut -c1-150); printf '%s\t%s\t%s\n' "$id" "$rc" "$last"; }
if [ -z "${ONLY:-}" ]; then
run 1 60 $BIN/train_maze --size 8 --mazes 0 --steps 2 --out $T/m.safetensors
run 2a 20 $BIN/fmm $T/grid.txt --repeat 18446744073709551615
run 2b 20 $BIN/fmm $T/grid.txt --repeat 100000000000
run 3a 20 $BIN/room --points 18446744073709551615 --out $T/r
run 3b 20 $BIN/room --points 10000000000 --out $T/r
run 4a 60 $BIN/room --body-radius 1e30 --out $T/r
run 4b 20 $BIN/room --body-radius 100 --out $T/r
run 5 120 $BIN/maze_nav --mazes $T/big.txt --planner field --rule strict
run 6a 20 $BIN/maze_nav --count 100000000000 --size 8 --planner astar
run 6b 20 $BIN/maze_nav --pairs 100000000000 --size 8 --planner astar
run 6c 60 $BIN/train_maze --size 8 --mazes 4 --steps 1 --batch 100000000 --queries 1000000 --out $T/m.safetensors
run 6d 60 $BIN/train_maze --size 8 --mazes 4 --steps 1 --encoder "100000000x[16:1]" --out $T/m.safetensors
run 7 60 $BIN/maze_nav --size 8 --count 20 --planner vin --model $T/broken.safetensors
cp models/hyper.safetensors $T/good.safetensors
run 8a 60 $BIN/train_vin --size 8 --mazes 10 --epochs 0 --eval-mazes 5 --out $T/good.safetensors
printf '8a-kept\t%s\t%s\n' "$(cmp -s models/hyper.safetensors $T/good.safetensors; echo $?)" "$(cmp -s models/hyper.safetensors $T/good.safetensors && echo file kept || echo file replaced)"
cp models/hyper.safetensors $T/good.safetensors
run 8b 60 $BIN/train_maze --size 8 --mazes 4 --steps 0 --out $T/good.safetensors
printf '8b-kept\t%s\t%s\n' "$(cmp -s models/hyper.safetensors $T/good.safetensors; echo $?)" "$(cmp -s models/hyper.safetensors $T/good.safetensors && echo file kept || echo file replaced)"
run 9 60 $BIN/train_maze --size 8 --mazes 4 --steps 2 --eval-mazes 0 --out $T/m9.safetensors
run 10a 20 $BIN/maze_nav --count 0 --size 8 --planner astar
run 10b 20 $BIN/maze_nav --mazes $T/wall.txt --planner astar
rm -f $T/f.npy
run 11 20 $BIN/fmm $T/pic.txt --spacing 1e38 --out $T/f.npy
printf '11-nan\t-\t%s\n' "$(python3 -c "
import struct,math,sys
try: b=open('$T/f.npy','rb').read()
except OSError: print('no field written'); sys.exit()
n=struct.unpack('<H',b[8:10])[0]; v=struct.unpack('<%df'%((len(b)-10-n)//4), b[10+n:])
print(sum(1 for x in v if math.isnan(x)),'NaN cells in the field written')")"
$BIN/train_vin --size 8 --mazes 10 --max-steps 3 --eval-mazes 5 --out $T/v8.safetensors > /dev/null 2>&1
run 12a 60 $BIN/train_vin --size 16 --mazes 10 --max-steps 6 --eval-mazes 5 --resume $T/v8.safetensors.ckpt --out $T/v16.safetensors
run 12b 20 $BIN/fmm $T/two.txt
echo keep > $T/victim.txt
run 13 20 sh -c "ln -sf $T/victim.txt $T/.f13.npy.\$\$.tmp; exec $BIN/fmm $T/grid.txt --out $T/f13.npy"
printf '13-victim\t-\t%s\n' "$(head -c 20 $T/victim.txt | tr -d '\n' | cut -c1-20)"
rm -f $T/.f13.npy.*.tmp
start=$(date +%s.%N); run 14a 120 $BIN/maze_nav --size 64 --count 5000 --planner astar,fmm --paths /nonexistent/p.json; printf '14a-time\t-\t%.1f s\n' "$(echo "$(date +%s.%N) - $start" | bc)"
mkdir -p $T/somedir
run 14b 120 $BIN/train_maze --size 8 --mazes 4 --steps 20 --out $T/somedir/
run 15a 20 $BIN/fmm $T/bad.png
run 15b 20 $BIN/fmm $T/float.npy
run 15c 60 $BIN/train_maze --size 8 --mazes 4 --steps 2 --lr=-1 --out $T/m15.safetensors
run 16 120 $BIN/maze_nav --generator perfect --size 41 --count 20 --png $T/out.png --paths $T/paths.json
fi
if [ -z "${ONLY:-}" ] || [ "${ONLY:-}" = 36 ]; then

# Issue 36: the room and crowd entry points.
huge=18446744073709551615
printf 'v 0 0 0\nv 100 0 0\nv 100 100 0\nv 0 100 0\nf 1 2 3\nf 1 3 4\nv 50 50 0\nv 51 50 0\nv 51 51 1\nf 5 6 7\n' > $T/big_room.obj
cp models/vae.safetensors $T/good_vae.safetensors
run 36-1 120 $BIN/train_vae --rooms 1 --steps 0 --out $T/good_vae.safetensors
printf '36-1-kept\t%s\t%s\n' "$(cmp -s models/vae.safetensors $T/good_vae.safetensors; echo $?)" "$(cmp -s models/vae.safetensors $T/good_vae.safetensors && echo file kept || echo file replaced)"
cp models/birdseye.safetensors $T/good_be.safetensors
run 36-2 120 $BIN/train_birdseye --rooms 2 --eval-rooms 2 --steps 0 --out $T/good_be.safetensors
printf '36-2-kept\t%s\t%s\n' "$(cmp -s models/birdseye.safetensors $T/good_be.safetensors; echo $?)" "$(cmp -s models/birdseye.safetensors $T/good_be.safetensors && echo file kept || echo file replaced)"
run 36-9 60 $BIN/room_nav --pairs 0 --json --out $T/rn9
run 36-10 120 $BIN/room_nav --field-steps 0 --json --out $T/rn10
run 36-11 60 $BIN/birdseye_multi --seed $huge --rooms 2 --json --out $T/be11
run 36-12 120 $BIN/suite --seed $huge --count 2 --no-vin --only "perfect 21"
run 36-13 120 $BIN/train_birdseye --rooms 2 --eval-rooms 0 --steps 2 --out $T/be13.safetensors
run 36-14a 60 $BIN/birdseye_multi --directions $huge --out $T/be14
run 36-14b 60 $BIN/train_vae --rooms 1 --scenes $huge --out $T/v14.safetensors
run 36-14c 60 $BIN/train_vae --rooms 1 --torsos $huge --out $T/v14.safetensors
run 36-15 60 $BIN/train_vae --rooms 1 --scenes 16 --torsos 10000000 --out $T/v15.safetensors
run 36-16a 60 $BIN/train_birdseye --goals-per-room $huge --out $T/be16.safetensors
run 36-16b 60 $BIN/train_birdseye --rooms $huge --out $T/be16.safetensors
run 36-17 60 $BIN/birdseye_multi --room $T/big_room.obj --out $T/be17
run 36-5 60 $BIN/accessible --scene $T/big_room.obj --no-field --out $T/acc5
# Case 4: a 1 cm cube alone, and one floating table top (1.2 x 0.8 x 0.04 m, 0.70 m up).
printf 'v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nv 0 0.01 0\nv 0 0 0.01\nv 0.01 0 0.01\nv 0.01 0.01 0.01\nv 0 0.01 0.01\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n' > $T/cube.obj
run 36-4a 120 $BIN/accessible --scene $T/cube.obj --no-field --out $T/acc4a
printf 'v 0 0 0.7\nv 1.2 0 0.7\nv 0 0.8 0.7\nv 1.2 0.8 0.7\nv 0 0 0.74\nv 1.2 0 0.74\nv 0 0.8 0.74\nv 1.2 0.8 0.74\nf 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 2 4 8\nf 2 8 6\nf 4 3 7\nf 4 7 8\nf 3 1 5\nf 3 5 7\n' > $T/top.obj
run 36-4b 120 $BIN/accessible --scene $T/top.obj --no-field --json --out $T/acc4b
# Recast's levels (scripts/fetch_recast_levels.sh): a region from their surfaces.
if [ -f data/recast/dungeon.obj ]; then
    run 36-6a 300 $BIN/level --scene data/recast/dungeon.obj --json --out $T/lv6a
    run 36-6b 300 $BIN/level --scene data/recast/nav_test.obj --json --out $T/lv6b
fi
run 36-18 60 $BIN/train_birdseye --rooms 2 --eval-rooms 2 --steps 10 --resume --out $T/be18.safetensors

fi
if [ -z "${ONLY:-}" ] || [ "${ONLY:-}" = 56 ]; then
# Issue 56: nothing a user saved is lost.
huge=18446744073709551615
printf 'v 0 0 0\nv 4 0 0\nv 4 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n' > $T/scene.obj; cp $T/scene.obj $T/scene.orig
echo "old records" > $T/walks.jsonl
run 56-1a 60 $BIN/room_nav --scene $T/missing.obj --walks-out $T/walks.jsonl --out $T/n1
printf '56-1a-kept\t%s\t%s\n' 0 "$(cat $T/walks.jsonl)"
run 56-1b 60 $BIN/room_nav --scene $T/scene.obj --walks-out $T/scene.obj --out $T/n1
run 56-2a 60 $BIN/room --scene $T/scene.obj --out $T
run 56-2b 60 $BIN/accessible --scene $T/scene.obj --no-field --out $T
run 56-2c 60 $BIN/level --scene $T/scene.obj --up z --out $T
run 56-2d 60 $BIN/room_nav --scene $T/scene.obj --out $T
printf '56-2-kept\t%s\t%s\n' "$(cmp -s $T/scene.obj $T/scene.orig; echo $?)" "$(cmp -s $T/scene.obj $T/scene.orig && echo scene kept || echo scene replaced)"
run 56-3a 120 $BIN/train_vin --size 8 --mazes 8 --eval-mazes 4 --max-steps 3 --out $T/v56.safetensors
cp $T/v56.safetensors $T/v56.orig
run 56-3b 120 $BIN/train_vin --size 8 --mazes 8 --eval-mazes 4 --max-steps 3 --resume $T/v56.safetensors.ckpt --out $T/v56.safetensors
printf '56-3b-kept\t%s\t%s\n' "$(cmp -s $T/v56.safetensors $T/v56.orig; echo $?)" "$(cmp -s $T/v56.safetensors $T/v56.orig && echo file kept || echo file replaced)"
run 56-3c 120 $BIN/train_maze --arch plain --size 8 --steps 3 --out $T/m56.safetensors
cp $T/m56.safetensors $T/m56.orig
run 56-3d 120 $BIN/train_maze --arch plain --size 8 --steps 3 --resume $T/m56.safetensors.ckpt --out $T/m56.safetensors
printf '56-3d-kept\t%s\t%s\n' "$(cmp -s $T/m56.safetensors $T/m56.orig; echo $?)" "$(cmp -s $T/m56.safetensors $T/m56.orig && echo file kept || echo file replaced)"
# Panics, aborts and hangs.
printf 'v 0 0 0\nv 4e20 0 0\nv 4e20 3 0\nf 1 2 3\n' > $T/far.obj
run 56-4a 60 $BIN/room --scene $T/far.obj --out $T/r4
cp $T/scene.orig $T/unit.obj
run 56-4b 60 $BIN/room --scene $T/unit.obj --units 1e30 --out $T/r4
run 56-5 60 $BIN/train_vin --eval-mazes $huge --out $T/v5.safetensors
printf 'v 0 0 0\nv 800 0 0\nv 800 600 0\nv 0 600 0\nf 1 2 3\nf 1 3 4\n' > $T/wide.obj
run 56-6 60 $BIN/level --scene $T/wide.obj --up z --out $T/l6
run 56-7 60 $BIN/room_nav --big-budget 1000000000 --out $T/n7
# Flags that would be ignored.
run 56-8a 60 $BIN/accessible --scene $T/unit.obj --rooms 1 --out $T/a8
run 56-8b 60 $BIN/accessible --field-steps 0 --out $T/a8
run 56-8c 60 $BIN/birdseye_multi --room $T/unit.obj --rooms 2 --out $T/b8
run 56-8d 60 $BIN/room_nav --save-field $T/f8.safetensors --rooms 2 --out $T/n8
# The up axis, tilt and units: a generated room written as files of other frames.
$BIN/room --out $T/g9 > /dev/null 2>&1
python3 - "$T" <<'PY'
import math, sys
t = sys.argv[1]
vs, fs = [], []
for line in open(f"{t}/g9/scene.obj"):
    p = line.split()
    if p and p[0] == "v":
        vs.append(tuple(map(float, p[1:4])))
    elif p and p[0] == "f":
        fs.append(line)
def write(name, f, faces=fs):
    with open(f"{t}/{name}", "w") as out:
        out.writelines("v %f %f %f\n" % f(*v) for v in vs)
        out.writelines(faces)
c, s = math.cos(math.radians(10)), math.sin(math.radians(10))
write("yup.obj", lambda x, y, z: (x, z, -y))
write("tilt.obj", lambda x, y, z: (x, c * y - s * z, s * y + c * z))
write("micro.obj", lambda x, y, z: (x, y, z))
def boxes(name, bs, extra=""):
    with open(f"{t}/{name}", "w") as out:
        n = 0
        for lo, hi in bs:
            for k in range(8):
                out.write("v %f %f %f\n" % tuple(hi[a] if k >> a & 1 else lo[a] for a in range(3)))
            for q in [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]:
                out.write("f %d %d %d %d\n" % tuple(n + 1 + i for i in q))
            n += 8
        out.write(extra)
wall = lambda x0, y0, x1, y1: ((x0, y0, 0), (x1, y1, 2.5))
# A corridor 10 x 1.2 m, its long walls along x (once told "is the scene y-up?").
boxes("corridor.obj", [((0, 0, -0.1), (10, 1.2, 0)), wall(0, -0.1, 10, 0), wall(0, 1.2, 10, 1.3)])
# Ten solid steps on a landing.
boxes("stairs.obj", [((0, 0, -0.1), (4, 1, 0))] + [((1 + 0.3 * k, 0, 0), (4, 1, 0.18 * (k + 1))) for k in range(10)])
# Two 3 x 3 m rooms joined by a 0.2 m slot, and by a 0.1 m one.
boxes("slot.obj", [((0, 0, -0.1), (6.3, 3, 0)), wall(3, 0, 3.3, 1.4), wall(3, 1.6, 3.3, 3)])
boxes("slot1.obj", [((0, 0, -0.1), (6.3, 3, 0)), wall(3, 0, 3.3, 1.45), wall(3, 1.55, 3.3, 3)])
# A 50 x 50 m warehouse.
boxes("warehouse.obj", [((0, 0, -0.1), (50, 50, 0)), wall(0, -0.1, 50, 0), ((10, 10, 0), (12, 11, 2))])
# A room whose floor is a 10-degree ramp.
r = 4 * math.tan(math.radians(10))
boxes("ramp.obj", [wall(0, -0.1, 4, 0), wall(0, 3, 4, 3.1)],
      "v 0 0 0\nv 4 0 %f\nv 4 3 %f\nv 0 3 0\nf 17 18 19 20\n" % (r, r))
PY
runw 56-9a 120 $BIN/room --scene $T/yup.obj --out $T/r9
runw 56-9b 120 $BIN/room --scene $T/yup.obj --up y --out $T/r9
runw 56-9c 120 $BIN/room --scene $T/g9/scene.obj --up y --out $T/r9
runw 56-9d 120 $BIN/room --scene $T/corridor.obj --out $T/r9
runw 56-9e 120 $BIN/level --scene $T/stairs.obj --up z --out $T/r9
if [ -f data/recast/dungeon.obj ]; then
    runw 56-9f 300 $BIN/level --scene data/recast/dungeon.obj --out $T/r9
fi
runw 56-10a 120 $BIN/room --scene $T/tilt.obj --out $T/r10
runw 56-10b 120 $BIN/room --scene $T/ramp.obj --out $T/r10
run 56-10c 120 $BIN/room --scene $T/ramp.obj --out $T/r10
run 56-11a 120 $BIN/accessible --scene $T/slot.obj --no-field --json --out $T/r11
runw 56-11b 120 $BIN/accessible --scene $T/slot1.obj --no-field --out $T/r11
start=$(date +%s); run 56-12 120 $BIN/room_nav --scene $T/warehouse.obj --pairs 2 --out $T/r12; printf '56-12-time\t-\t%s s\n' $(( $(date +%s) - start ))
runw 56-13a 60 $BIN/room --scene $T/micro.obj --units 1e-6 --out $T/r13
run 56-13b 60 $BIN/room --scene $T/micro.obj --units 1e-6 --out $T/r13
run 56-14 300 $BIN/room_nav --field models/context.safetensors --pairs 2 --planners ours --out $T/r14
fi
