# Sourced by the ensure-*.sh scripts: installs one Debian package that a check found
# missing, or, where that cannot be done here (no root and no non-interactive sudo, or
# no apt-get), says what is missing and how to install it, and exits with status 2.
# Only builtins and apt-get, so it runs with the narrow PATH the scripts' tests give it.
#
# Usage: apt_install "<what is missing>" <package> "<install hint>"
apt_install() {
  local missing=$1 package=$2 hint=$3 sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
      sudo="sudo"
    else
      echo "error: $missing, and installing it needs root or sudo." >&2
      echo "$hint" >&2
      exit 2
    fi
  fi
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "error: $missing, and apt-get is not available here." >&2
    echo "$hint" >&2
    exit 2
  fi
  echo "$missing: installing $package" >&2
  $sudo apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$package" >/dev/null
}
