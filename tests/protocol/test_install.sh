#!/usr/bin/env bash
# `make install` gives a third-party solver everything it needs: headers, the static protocol
# library and a pkg-config file, the conformance harness netcouple-check, and the Python
# participant module where Debian's /usr/bin/python3 finds it, with the spring-plate example.
# Builds a minimal participant against the installed copy only and runs it until its idle
# timeout; imports the installed Python module and runs netcouple-check (installed) on the
# installed example, which finds the module through the install location alone.
# The release build and install run in a copy of the source tree: the suite may be using the
# programs of the working tree (bin/, build/) at the same time, and this test must leave them
# exactly as they were (checked: every file under bin/ and build/ keeps its size and mtime).
set -eu
prefix="$NC_TMP/prefix"
src="$NC_TMP/src"
snapshot() {   # every file under bin/ and build/ of the working tree, with size and mtime
  (cd "$NC_ROOT" && find bin build -type f -printf '%p %s %T@\n' 2>/dev/null | sort)
}
snapshot > "$NC_TMP/before.txt"
# sources as they are (mtimes kept), and the release build so that only what changed is rebuilt
mkdir -p "$src/build"
tar -C "$NC_ROOT" --exclude=./.git --exclude=./build --exclude=./runs --exclude=./results -cf - . \
  | tar -C "$src" -xf -
[ -d "$NC_ROOT/build/release" ] && cp -a "$NC_ROOT/build/release" "$src/build/"
# a release build/install, whatever build the test suite itself runs under
env -u MAKEFLAGS -u MAKELEVEL -u SANITIZE make -s -C "$src" install PREFIX="$prefix" >"$NC_TMP/install.log" 2>&1 || {
  cat "$NC_TMP/install.log"; exit 1; }
snapshot > "$NC_TMP/after.txt"
diff "$NC_TMP/before.txt" "$NC_TMP/after.txt" >"$NC_TMP/changed.txt" || {
  echo "make install changed the working tree's bin/ or build/:"; head -n 20 "$NC_TMP/changed.txt"; exit 1; }
site=$(/usr/bin/python3 -c 'import sys; print("lib/python%d.%d/dist-packages" % sys.version_info[:2])')
examples=share/doc/netcouple/examples
for f in bin/fem_solver bin/dem_solver bin/coupler bin/netcouple-check lib/libnetcouple_protocol.a \
         "$site/netcouple_participant.py" "$examples/spring_plate.py" "$examples/ball_dem.py" \
         "$examples/plate.json" "$examples/ball.json" share/doc/netcouple/netcouple-check.md \
         include/netcouple/proto.h include/netcouple/proto_serve.h include/netcouple/nc_error.h \
         lib/pkgconfig/netcouple-protocol.pc share/doc/netcouple/protocol.md; do
  [ -e "$prefix/$f" ] || { echo "missing after install: $f"; exit 1; }
done
cat > "$NC_TMP/third_party.c" <<'C'
#include <proto.h>
#include <stdio.h>
#include <string.h>
int main(void)
{
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = 200;
    proto_participant *p;
    nc_error err;
    if (proto_participant_open(&p, "tcp://127.0.0.1:*", "fem", "third party", "", &options, &err)) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    proto_message command;
    memset(&command, 0, sizeof command);
    int rc = proto_participant_receive(p, &command, &err);
    proto_participant_close(p);
    /* nobody connects: the idle timeout must fire with its message */
    if (rc == -1 && err.code == PROTO_ERR_IDLE && strstr(err.message, "idle timeout")) return 0;
    fprintf(stderr, "unexpected: rc %d, %s\n", rc, err.message);
    return 1;
}
C
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# shellcheck disable=SC2046
cc -o "$NC_TMP/third_party" "$NC_TMP/third_party.c" $(pkg-config --cflags --libs netcouple-protocol)
"$NC_TMP/third_party"
echo "third-party participant built from the installed library and ran"

# the Python module: importable from the install location by Debian's interpreter
PYTHONPATH="$prefix/$site" /usr/bin/python3 -c 'import netcouple_participant as m; print(m.__file__)' \
  >"$NC_TMP/import.txt" 2>&1 || { cat "$NC_TMP/import.txt"; exit 1; }
grep -q "^$prefix/$site/netcouple_participant.py" "$NC_TMP/import.txt" || {
  echo "imported another copy: $(cat "$NC_TMP/import.txt")"; exit 1; }
# that location is on Debian's sys.path when PREFIX is /usr/local
/usr/bin/python3 -c 'import sys; sys.exit(0 if "/usr/local/'"$site"'" in sys.path else 1)' || {
  echo "/usr/local/$site is not on /usr/bin/python3's sys.path"; exit 1; }
# the example next to no copy of the module: it runs on the installed one, and conforms
PYTHONPATH="$prefix/$site" "$prefix/bin/netcouple-check" --no-idle-check --work "$NC_TMP/check" \
  -- /usr/bin/python3 "$prefix/$examples/spring_plate.py" "$prefix/$examples/plate.json" \
  >"$NC_TMP/check.out" 2>&1 || { cat "$NC_TMP/check.out"; exit 1; }
grep -q "PASS  restore: solve repeated" "$NC_TMP/check.out" || { cat "$NC_TMP/check.out"; exit 1; }
echo "installed netcouple-check passed on the installed spring_plate.py example"
