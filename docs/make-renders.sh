#!/usr/bin/env bash
# Draws the pictures in docs/ that show the sky (the sky's contact sheet by
# make-sky-contact-sheet.sh, and the clouds, GPU, table and window pictures that have
# the sky in them) with the release binary (cargo build --release -p atmo-cli), then
# assembles the multi-panel ones with ImageMagick's montage. The window's pictures need
# a display: run under xvfb-run -s '-screen 0 1280x800x24' (the embedding example's
# window is 800 x 600). Run from the repository's root.
set -euo pipefail
atmo=${ATMO:-target/release/atmo}
r=docs/renders
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

ATMO=$atmo bash docs/make-sky-contact-sheet.sh

# The clouds: in front of the sky, against the sun and from its side; the shadow.
"$atmo" clouds --generate cumulus --sky --view-height 300 --width 640 --height 360 -o "$tmp/c1.png"
"$atmo" clouds --generate cumulus --sky --view-height 300 --width 640 --height 360 \
    --sun-elevation 8 --sun-azimuth 90 -o "$tmp/c2.png"
montage "$tmp/c1.png" "$tmp/c2.png" -tile 2x1 -geometry +0+0 "$r/clouds-sky.png"
"$atmo" clouds --generate cumulus --sky --ground-albedo 0.2 --camera -6000,3000,3000 \
    --look-at -1000,900,-500 --fov 50 --sun-elevation 30 --sun-azimuth 150 \
    --width 640 --height 360 -o "$r/clouds-shadow.png"
# On black, lit from behind the camera: single scattering and every order.
for s in single solve; do
    "$atmo" clouds --generate cumulus --sun-azimuth 200 --sun-elevation 30 --distance 1.2 \
        --view-height 1200 --width 640 --height 360 --scattering $s -o "$tmp/f-$s.png"
done
montage "$tmp/f-single.png" "$tmp/f-solve.png" -tile 2x1 -geometry +0+0 "$r/clouds-first.png"
# The solve's default with the sky: side-lit, back-lit (the sun behind the cloud), from below.
"$atmo" clouds --generate cumulus --sky --view-height 1200 --sun-elevation 20 --sun-azimuth 130 \
    --width 480 --height 270 -o "$tmp/v-side.png"
"$atmo" clouds --generate cumulus --sky --view-height 1200 --sun-elevation 15 --sun-azimuth 20 \
    --width 480 --height 270 -o "$tmp/v-back.png"
"$atmo" clouds --generate cumulus --sky --camera -1500,300,1500 --look-at 0,1500,0 --fov 60 \
    --width 480 --height 270 -o "$tmp/v-below.png"
montage "$tmp"/v-{side,back,below}.png -tile 3x1 -geometry +2+2 -background '#202020' \
    "$r/clouds-views.png"
# Every order by the transfer solve and by the table, on black, the sun from the side.
for s in solve multiple; do
    "$atmo" clouds --generate cumulus --sun-elevation 20 --sun-azimuth 130 --scattering $s \
        --width 640 --height 360 -o "$tmp/o-$s.png"
done
montage "$tmp/o-solve.png" "$tmp/o-multiple.png" -tile 2x1 -geometry +0+0 "$r/clouds-solve.png"

# On the GPU (lavapipe where there is no other adapter).
"$atmo" sky --backend gpu --sun-elevation 3 --sun-azimuth 180 --altitude 3000 --yaw 180 \
    --pitch -5 --width 400 --height 225 -o "$tmp/g1.png"
"$atmo" shafts scenes/stage.toml --backend gpu --set camera.width=400 \
    --set camera.height=225 -o "$tmp/g2.png"
"$atmo" clouds --generate cumulus --sky --view-height 300 --backend gpu --width 400 \
    --height 225 -o "$tmp/g3.png"
montage "$tmp"/g{1,2,3}.png -tile 3x1 -geometry +3+3 -background '#202020' \
    "$r/gpu-llvmpipe.png"

# From the table: a sunset from 3 km and a climb, eight frames each; the paper's Fig. 10.
"$atmo" precompute sky -o "$tmp/earth.atmo-sky"
"$atmo" sky --table "$tmp/earth.atmo-sky" --animate sun --sun-elevation 20 --altitude 3000 \
    --frames 8 --width 320 --height 180 -o "$tmp/sunset/"
"$atmo" sky --table "$tmp/earth.atmo-sky" --animate altitude --sun-elevation 8 \
    --frames 8 --width 320 --height 180 -o "$tmp/climb/"
montage "$tmp"/sunset/frame-000?.png "$tmp"/climb/frame-000?.png -tile 8x2 -geometry +2+2 \
    -background '#202020' docs/sky-table-sunset.png
"$atmo" inspect "$tmp/earth.atmo-sky" --sun-elevation -3.55 --altitude 10593 --plots "$tmp/plots"
montage "$tmp"/plots/{direct,table,error,terms}.png -tile 4x1 -geometry 256x256+0+0 \
    "$r/sky-table-fig10.png"

# The window (needs a display).
printf '1 key right\n2 key right\n' > "$tmp/sun.txt"
"$atmo" view clouds --scene scenes/cumulus.toml --width 960 --height 600 --frames 4 \
    --script "$tmp/sun.txt" --screenshot "$r/view-clouds.png"
"$atmo" view sky --sun-elevation 3 --altitude 2000 --pitch 5 --exposure 0.3 --backend cpu \
    --frames 2 --screenshot "$r/view-sky.png"

# The embedding example (a window of its own, no screenshot key): its window grabbed
# from the display after it has drawn (cargo build --release -p atmo-gpu --example embed).
target/release/examples/embed &
embed=$!
sleep 40
import -window root "$tmp/root.png"
kill "$embed"
convert "$tmp/root.png" -crop 800x600+0+0 +repage "$r/embed-aerial.png"
