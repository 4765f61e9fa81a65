#!/bin/sh
# Build both Box2D builds of vs-peers and run the SSE2 one with the AVX2 one as its child, so
# that one run times tiltbox, Box2D v3 SSE2, Box2D v3 AVX2 and rapier2d chunk by chunk in turn.
# Arguments go to vs-peers, e.g. `./run.sh --no-extras large_pyramid`.
# PROFILE=quick builds without LTO (for development; not for figures).
set -e
cd "$(dirname "$0")"
profile="${PROFILE:-release}"
# boxdd-sys compiles Box2D's C once per feature set; cargo keeps both, so switching back and
# forth only relinks vs-peers.
cargo build --profile "$profile" --features avx2
mkdir -p target/avx2
cp "target/$profile/vs-peers" target/avx2/vs-peers
cargo build --profile "$profile"
exec "target/$profile/vs-peers" --avx2 target/avx2/vs-peers "$@"
