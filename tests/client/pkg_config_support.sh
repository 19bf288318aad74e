# What the pkg_config_test.sh scripts share, sourced with their arguments: BUILD_DIR PKG_CONFIG
# C_COMPILER CXX_COMPILER [BUILD_FLAGS] (BUILD_FLAGS: what a sanitized build's programs need,
# -fsanitize=..., nothing of the API). It sets build, pkg_config, cc, cxx and build_flags from
# them, makes the scratch folder $out (removed on exit) and points pkg-config at the build
# tree's .pc files alone.
build=$1
pkg_config=$2
cc=$3
cxx=$4
build_flags=${5:-}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
export PKG_CONFIG_PATH=$build/lib/pkgconfig
