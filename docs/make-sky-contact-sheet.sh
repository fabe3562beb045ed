#!/usr/bin/env bash
# Draws docs/sky-contact-sheet.png and its nine pictures in docs/renders/ with the
# release binary (cargo build --release -p atmo-cli), then assembles them with
# ImageMagick's montage. Run from the repository's root.
set -euo pipefail
atmo=${ATMO:-target/release/atmo}
r=docs/renders
sky() { out=$1; shift; "$atmo" sky --width 480 --height 270 "$@" -o "$r/$out.png"; }
sky day-7km --sun-elevation 30 --altitude 7000
sky sun5-4km --sun-elevation 5 --altitude 4000 --exposure 0.3
sky below-horizon-13km --sun-elevation 20 --altitude 13000 --pitch -3
sky order1 --sun-elevation 30 --order 1 --yaw 0 --pitch 30
sky order2 --sun-elevation 30 --order 2 --yaw 0 --pitch 30
sky order-all --sun-elevation 30 --yaw 0 --pitch 30
sky sunset-paper --sun-elevation 1 --exposure 0.2 --order 2 --no-ozone
sky sunset --sun-elevation 1 --exposure 0.2
"$atmo" sky --width 270 --height 270 --sun-elevation 45 --sun-azimuth 150 --fisheye -o "$r/dome.png"
"$atmo" sky --sun-elevation 25 --altitude 5000 --pitch -8 --width 480 --height 270 \
    -o "$r/sky-every-order-ground.png"
montage "$r"/{day-7km,sun5-4km,below-horizon-13km,order1,order2,order-all,sunset-paper,sunset,dome}.png \
    -tile 3x3 -geometry 480x270+4+4 -background '#202020' docs/sky-contact-sheet.png
