#!/bin/sh
# Old against new tiltbox, by the benchmark rule: whole processes of `examples/profile_step`
# alternated on one pinned core, ROUNDS rounds (default 5), the median ms/step of each run,
# every round printed, then the median of each build's medians and their ratio (new / old).
# The state hash each run prints tells whether a change meant to be bit-identical is.
#
#   benchmarks/ab.sh OLD_REV [SCENE...]      # OLD_REV against the working tree
#   ROUNDS=7 CORE=0 STEPS=300 benchmarks/ab.sh HEAD~3 pyramid_20 many_boxes
#
# Both builds use the bench profile (fat LTO), as vs-peers does. The old revision is checked
# out in target/ab/old-src (a git worktree) and built into target/ab/old, with this tree's
# examples/profile_step.rs (measurement, not engine), so both print alike.
set -eu
cd "$(dirname "$0")/.."
old_rev=${1:?usage: benchmarks/ab.sh OLD_REV [SCENE...]}
shift
# Resolved here: inside the worktree, a name like HEAD would mean the worktree's own.
old_sha=$(git rev-parse --verify "$old_rev^{commit}")
scenes=${*:-large_pyramid pyramid_20 falling_bricks many_boxes resting_pyramid mixed_shapes}
rounds=${ROUNDS:-5}
core=${CORE:-1}
steps=${STEPS:-500}
build="cargo build --profile bench --no-default-features --features measure --example profile_step"

root=$(pwd)
mkdir -p target/ab
if [ -d target/ab/old-src ]; then
    git -C target/ab/old-src checkout -q -f --detach "$old_sha"
else
    git worktree add -q --detach target/ab/old-src "$old_sha"
fi
cp examples/profile_step.rs target/ab/old-src/examples/profile_step.rs
(cd target/ab/old-src && CARGO_TARGET_DIR="$root/target/ab/old" $build >&2)
$build >&2
old=target/ab/old/release/examples/profile_step
[ -x "$old" ] || old=target/ab/old/bench/examples/profile_step
new=target/bench/examples/profile_step
[ -x "$new" ] || new=target/release/examples/profile_step

echo "old: $old_rev ($(git rev-parse --short "$old_sha")), new: working tree at $(git rev-parse --short HEAD)$(git diff --quiet || echo ' + changes')"
echo "core $core, $rounds rounds, $steps timed steps a run; $(uptime | sed 's/.*load/load/')"
for scene in $scenes; do
    olds=""
    news=""
    for r in $(seq "$rounds"); do
        o=$(taskset -c "$core" "$old" "$scene" "$steps")
        n=$(taskset -c "$core" "$new" "$scene" "$steps")
        om=$(echo "$o" | sed 's/.*median \([0-9.]*\) ms.*/\1/')
        nm=$(echo "$n" | sed 's/.*median \([0-9.]*\) ms.*/\1/')
        oh=$(echo "$o" | sed 's/.*state \([0-9a-f]*\).*/\1/')
        nh=$(echo "$n" | sed 's/.*state \([0-9a-f]*\).*/\1/')
        echo "$scene round $r: old $om ms ($oh), new $nm ms ($nh)"
        olds="$olds $om"
        news="$news $nm"
    done
    median() { echo "$@" | tr ' ' '\n' | grep . | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
    mo=$(median $olds)
    mn=$(median $news)
    echo "$scene: median old $mo ms, new $mn ms, new / old $(awk "BEGIN {printf \"%.3f\", $mn / $mo}")"
done
