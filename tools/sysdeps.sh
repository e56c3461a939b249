#!/usr/bin/env bash
# System tools some features need (Debian packages). Installs the missing ones with
# apt-get when run as root; otherwise says what to install and goes on: the features
# that need a missing tool skip their tests with a message.
#   graphviz              `mechatron diagram` and the diagrams in reports
#   chromium              the browser test of generated reports
#   gcc-arm-none-eabi     cross-compiling generated C for a Cortex-M
#   libnewlib-arm-none-eabi  its C library
#   qemu-system-arm       processor-in-the-loop runs on an emulated board
set -u
PACKAGES="graphviz chromium gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
missing=""
for p in $PACKAGES; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" \
        || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
if ! command -v apt-get >/dev/null 2>&1; then
    echo "note: no apt-get here; install these for the full feature set:$missing" >&2
    exit 0
fi
if [ "$(id -u)" != "0" ]; then
    echo "note: not root, so not installing:$missing (features that need them skip" \
         "their tests; run 'sudo apt-get install$missing' to get them)" >&2
    exit 0
fi
echo "installing system packages:$missing"
export DEBIAN_FRONTEND=noninteractive
if ! apt-get install -y -qq --no-install-recommends $missing >/dev/null 2>&1; then
    apt-get update -qq >/dev/null 2>&1
    apt-get install -y -qq --no-install-recommends $missing >/dev/null 2>&1 \
        || echo "note: apt-get could not install some of:$missing (features that need" \
                "them skip their tests)" >&2
fi
exit 0
