#!/usr/bin/env bash
# A participant that never publishes its endpoint (a solver still reading a huge input): it
# just waits, as the same process (exec), so that a signal to it ends it. Takes the solvers'
# arguments and ignores them.
exec sleep 60
