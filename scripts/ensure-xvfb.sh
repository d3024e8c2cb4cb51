#!/usr/bin/env bash
# Makes sure Xvfb (the X server without a screen) exists, for the viewer's tests and for
# running `meshlight view` on a machine without a display. With none installed, installs
# Debian's `xvfb` package; that needs root or sudo. Without either, or without apt-get,
# it says what to install and exits with status 2.
#
# With `--start`, it also starts Xvfb on the first free display number from 99 up and
# prints that number (e.g. `:99`); the server's process id is written to the file named
# by XVFB_PID_FILE when set. The caller stops it.
set -euo pipefail

install_hint="install Xvfb, e.g.
  sudo apt-get install xvfb                    (Debian, Ubuntu)
  sudo dnf install xorg-x11-server-Xvfb        (Fedora)
  sudo pacman -S xorg-server-xvfb              (Arch)"

if ! command -v Xvfb >/dev/null 2>&1; then
  here="${BASH_SOURCE[0]%/*}"
  [ "$here" = "${BASH_SOURCE[0]}" ] && here=.
  source "$here/apt-install.sh"
  apt_install "Xvfb is not installed" xvfb "$install_hint"
  if ! command -v Xvfb >/dev/null 2>&1; then
    echo "error: xvfb was installed but no Xvfb is on PATH" >&2
    exit 2
  fi
fi

if [ "${1:-}" != "--start" ]; then
  exit 0
fi

# A display is free when neither its lock file nor its socket exists.
for n in $(seq 99 199); do
  if [ -e "/tmp/.X$n-lock" ] || [ -e "/tmp/.X11-unix/X$n" ]; then
    continue
  fi
  Xvfb ":$n" -screen 0 1920x1080x24 -nolisten tcp >/dev/null 2>&1 &
  pid=$!
  # Ready when its socket appears; gone when another one took the number first.
  for _ in $(seq 1 100); do
    if [ -e "/tmp/.X11-unix/X$n" ]; then
      [ -n "${XVFB_PID_FILE:-}" ] && echo "$pid" >"$XVFB_PID_FILE"
      echo ":$n"
      exit 0
    fi
    if ! kill -0 "$pid" 2>/dev/null; then
      break
    fi
    sleep 0.1
  done
  kill "$pid" 2>/dev/null || true
done
echo "error: could not start Xvfb on any display from :99 to :199" >&2
exit 2
