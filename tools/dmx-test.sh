#!/usr/bin/env bash
# Live DMX from senders that atmo did not write: Python's `sacn` (E1.31) and
# `stupidArtnet` (Art-Net), from PyPI, sending over the loopback interface. Run by
# .ci/run after the tests, with the atmo they built.
#
#   tools/dmx-test.sh [ATMO]        (default target/debug/atmo)
#
# For each protocol: `atmo dmx record` listens on 127.0.0.1 while the sender sweeps
# spot 1 of scenes/dmx-rig.toml through three pans (16-bit, with tilt and dimmer set),
# holding each; then for each hold the frame `atmo shafts --dmx-file` renders at that
# time must equal (within 0.05 levels RMS) the still rendered with the fixture's start
# set to the pan and tilt the GDTF file's ranges give for those DMX values
# (-270 + 540 v / 65535 deg), and the three holds' pictures must differ (the beam
# moved). sACN also gets a hostile burst (cut, lying and random datagrams) mid-sweep,
# which must not stop the recording.
set -euo pipefail
cd "$(dirname "$0")/.."
atmo=$(realpath "${1:-target/debug/atmo}")
[ -x "$atmo" ] || { echo "dmx-test: no atmo binary at $atmo (build it first)" >&2; exit 1; }
say() { echo "dmx-test: $*"; }
fail() { echo "dmx-test: FAILED: $*" >&2; exit 1; }

venv=target/dmx-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q "sacn==1.11.0" "stupidArtnet==1.6.0"

work=$(mktemp -d /tmp/atmo-dmx.XXXXXX)
recorder=""
stop() {
  local rc=$?
  [ -n "$recorder" ] && kill "$recorder" 2>/dev/null || true
  rm -rf "$work"
  exit "$rc"
}
trap stop EXIT

small=(--set camera.width=240 --set camera.height=160 --backend cpu)
# The three holds: pan coarse and fine bytes; tilt 0x9c00 (about 29.5 deg), dimmer
# full, zoom 0 (8 deg); spots 2 and 3 dark.
pans=("64 0" "128 0" "200 17")
tilt_coarse=156
# Spots 2 and 3 as all-zero DMX leaves them: dark, at one end of pan, tilt and zoom
# (their bodies are in the picture).
dark="{ pan_deg = -270.0, tilt_deg = -135.0, zoom_deg = 8.0, dimmer = 0.0 }"

cat > "$work/send.py" <<'EOF'
"""Sweeps spot 1's pan by sACN or Art-Net; argv: protocol, port, then the pans."""
import socket, sys, time

protocol, port = sys.argv[1], int(sys.argv[2])
pans = [tuple(int(x) for x in p.split()) for p in sys.argv[3:]]
tilt = int(__import__("os").environ["TILT"])

def levels(coarse, fine):
    data = [0] * 512
    data[0], data[1], data[2], data[3], data[6] = coarse, fine, tilt, 0, 255
    return data

if protocol == "sacn":
    import sacn
    sender = sacn.sACNsender(bind_address="127.0.0.1", bind_port=0, fps=44)
    sender.start()
    sender.activate_output(1)
    sender[1].multicast = False
    sender[1].destination = "127.0.0.1"
    for k, (coarse, fine) in enumerate(pans):
        sender[1].dmx_data = tuple(levels(coarse, fine))
        time.sleep(0.6)
        if k == 0:
            # Hostile datagrams from another socket: cut, oversized, random.
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            for n in range(300):
                junk = bytes((n * 7 + i) % 256 for i in range((n * 37) % 1400))
                s.sendto(junk, ("127.0.0.1", 5568))
    sender.stop()
else:
    from stupidArtnet import StupidArtnet
    node = StupidArtnet("127.0.0.1", 0, 512, 30, True, False, port=port)
    for coarse, fine in pans:
        node.set(bytearray(levels(coarse, fine)))
        node.show()
        time.sleep(0.6)
EOF

for protocol in sacn artnet; do
  case $protocol in
    sacn) bind=127.0.0.1; port=5568 ;;
    artnet) port=16454; bind=127.0.0.1:$port ;;
  esac
  rec="$work/$protocol.dmx"
  "$atmo" dmx record --protocol "$protocol" --bind "$bind" --scene scenes/dmx-rig.toml \
    -o "$rec" --seconds 30 --idle 1.5 2> "$work/record.log" &
  recorder=$!
  sleep 0.5
  TILT=$tilt_coarse "$venv/bin/python" "$work/send.py" "$protocol" "$port" "${pans[@]}"
  wait "$recorder" || { cat "$work/record.log"; fail "$protocol: the recorder failed"; }
  recorder=""
  cat "$work/record.log"
  "$atmo" dmx info --frames "$rec" > "$work/info.txt"
  # Each hold's first frame: its time and pan bytes.
  k=0
  for pan in "${pans[@]}"; do
    read -r coarse fine <<< "$pan"
    t=$(awk -v c="$coarse" -v f="$fine" -v tl="$tilt_coarse" \
      '$1 == "frame" && $9 == c && $10 == f && $11 == tl {print $3; exit}' "$work/info.txt")
    [ -n "$t" ] || { cat "$work/info.txt"; fail "$protocol: no frame with pan $coarse $fine"; }
    # Half a second into the hold (the sender holds 0.6 s).
    at=$(awk -v t="$t" 'BEGIN {printf "%.6f", t + 0.3}')
    "$atmo" shafts scenes/dmx-rig.toml "${small[@]}" --dmx-file "$rec" --time "$at" \
      -o "$work/dmx-$k.exr" 2>/dev/null
    pan_deg=$(awk -v c="$coarse" -v f="$fine" 'BEGIN {printf "%.6f", -270 + 540 * (c * 256 + f) / 65535}')
    tilt_deg=$(awk -v c="$tilt_coarse" 'BEGIN {printf "%.6f", -135 + 270 * (c * 256) / 65535}')
    "$atmo" shafts scenes/dmx-rig.toml "${small[@]}" \
      --set "fixture[0].start={ pan_deg = $pan_deg, tilt_deg = $tilt_deg, zoom_deg = 8.0 }" \
      --set "fixture[1].start=$dark" --set "fixture[2].start=$dark" \
      -o "$work/still-$k.exr" 2>/dev/null
    rms=$("$atmo" compare "$work/dmx-$k.exr" "$work/still-$k.exr" --exposure 0.12 \
      | grep -oE 'rms [0-9.]+' | head -n 1 | awk '{print $2}')
    say "$protocol: pan $coarse/$fine at $t s = $pan_deg deg: DMX frame vs still $rms levels RMS"
    awk -v r="$rms" 'BEGIN {exit !(r < 0.05)}' \
      || fail "$protocol: the frame at pan $pan_deg deg is $rms levels RMS from the still"
    k=$((k + 1))
  done
  for pair in "0 1" "1 2"; do
    read -r a b <<< "$pair"
    moved=$("$atmo" compare "$work/dmx-$a.exr" "$work/dmx-$b.exr" --exposure 0.12 \
      | grep -oE 'rms [0-9.]+' | head -n 1 | awk '{print $2}')
    awk -v r="$moved" 'BEGIN {exit !(r > 1)}' \
      || fail "$protocol: holds $a and $b are only $moved levels RMS apart: the beam did not move"
  done
done
# The window: `atmo view stage --dmx artnet --record` under Xvfb while stupidArtnet moves
# two heads for 1.5 s; its last picture must equal, bit for bit, the recording
# rendered offline at the time the window last posed the heads.
cat > "$work/sweep.py" <<'EOF'
import sys, time
from stupidArtnet import StupidArtnet
node = StupidArtnet("127.0.0.1", 0, 512, 30, True, False, port=int(sys.argv[1]))
for k in range(30):
    data = [0] * 512
    data[0], data[2], data[6] = 40 + 4 * k, 156, 255
    data[10], data[12], data[16] = 200 - 3 * k, 150, 255
    node.set(bytearray(data))
    node.show()
    time.sleep(0.05)
EOF
(sleep 1; "$venv/bin/python" "$work/sweep.py" 16455) &
sender=$!
xvfb-run -a "$atmo" view stage scenes/dmx-rig.toml --dmx artnet --bind 127.0.0.1:16455 \
  --record "$work/window.dmx" --width 240 --height 160 --backend cpu --preview 1 \
  --frames 5000 --screenshot "$work/window.exr" --timings > "$work/timings.json"
wait "$sender"
cat "$work/timings.json"
posed=$(grep -oE '"dmx_posed_s":[0-9.e-]+' "$work/timings.json" | cut -d: -f2)
frames=$(grep -oE '"dmx_frames":[0-9.]+' "$work/timings.json" | cut -d: -f2)
awk -v f="$frames" 'BEGIN {exit !(f >= 10)}' || fail "the window took only $frames of the 30 frames sent"
"$atmo" shafts scenes/dmx-rig.toml "${small[@]}" --dmx-file "$work/window.dmx" \
  --time "$(awk -v t="$posed" 'BEGIN {printf "%.6f", t}')" -o "$work/offline.exr" 2>/dev/null
same=$("$atmo" compare "$work/window.exr" "$work/offline.exr" --exposure 0.12 \
  | grep -oE 'linear: rms [0-9.e-]+' | awk '{print $3}')
say "the window's last picture (heads posed at $posed s) vs the recording rendered offline: $same RMS"
awk -v r="$same" 'BEGIN {exit !(r == 0)}' \
  || fail "the recording renders $same RMS away from the window's picture"
say "passed: sACN and Art-Net from third-party senders drive the rig as its GDTF ranges say, and a recording renders as the window drew it"
