#!/usr/bin/python3
"""soak — kill and stall trials of scripts/run_case.sh at random moments (`make soak`).

    /usr/bin/python3 scripts/soak.py [--trials N] [--seed S] [--jobs J] [--keep]
                                     [--only FAULT:VICTIM ...] [--case DIR] [--dir DIR] [--bin DIR]

Each trial runs a short real coupled case (default tests/coupler/cases/small_net: fem_solver,
dem_solver and the coupler, 2-4 s) through scripts/run_case.sh into its own folder, with
short timeouts: coupler.json timeouts connect 4 s, reply 4 s, shutdown 2 s (--set); stall
limit NC_STALL_LIMIT_S 6 s (and the endpoint wait NC_ENDPOINT_WAIT_S); grace NC_STOP_GRACE_S 3 s; OMP_NUM_THREADS 1. run_case.sh passes
no --idle-timeout, so the solvers keep their default of 300 s. At a random moment, uniform
over the undisturbed run time measured at the start (the shortest of --jobs runs side by
side; start-up included), one fault hits one victim; the 13 classes are equally likely:

    SIGKILL, SIGTERM, SIGSTOP  x  fem_solver, dem_solver, coupler, run_case.sh
    SIGINT to run_case.sh's process group (a Ctrl-C on its terminal)

A victim that does not exist yet at the moment (the coupler starts after the solvers have
published their endpoints) is hit as soon as it appears. A stopped program is never resumed
by this script (run_case.sh has to stop it); a stopped run_case.sh itself is resumed after
the stall limit (a stopped supervisor cannot report anything), and must then carry on.

Expected exit status and verdict line (the first line of run_case.sh's output that starts
"run_case: failed", "stopped by user", "done" or "finished"):

    SIGKILL/SIGTERM/SIGSTOP fem_solver    1   run_case: failed: fem (...      (dem alike)
    SIGKILL coupler                       1   run_case: failed: coupler (exit 137 = SIGKILL...
    SIGTERM coupler                     130   run_case: stopped by user (SIGTERM)...
    SIGSTOP coupler                       1   run_case: failed: coupler (stalled: ...
    SIGINT group                        130   run_case: stopped by user (SIGINT)...
    SIGTERM run_case.sh                 130   run_case: stopped by user (SIGTERM)...
    SIGSTOP run_case.sh (resumed)         0   run_case: done...
    SIGKILL run_case.sh                  -9   (no verdict; its orphans must end by themselves)
    a fault that found its victim gone    0   run_case: done...  ("missed": the trial is
                                              then repeated, at most twice, at the same
                                              fraction of the run time the missed run took)

also accepted: "done" (exit 0) for a SIGTERM, SIGINT or a solver's SIGKILL sent once the run
was complete (the coupler finishing or ended: the victim may have exited cleanly first);
"failed: coupler (exit 143 = SIGTERM" for a SIGTERM before the coupler wrote its progress
file (before its signal handler the signal ends it); death by the signal, no verdict, for
SIGINT/SIGTERM to run_case.sh before it started any program (before its traps).

Each trial is classified:
- hang: run_case.sh still running at the bound + 60 s; everything of the trial is killed;
- late: run_case.sh ended after the bound (the stop latency, fault to exit, is over it);
- leftover: a process of the trial (found by the environment variable NC_SOAK_TRIAL, which
  every process started by run_case.sh inherits) still alive 0.2 s after run_case.sh exited;
  after SIGKILL of run_case.sh, still alive at the bound (the orphans may finish the run);
- unreadable: an existing fem.h5, dem.h5 or coupling.h5 that h5py cannot open and read in
  full, or an existing fem.xdmf, particles.xdmf or dem_net.xdmf that tests/xdmf_check.py
  rejects (a stopped run has fewer steps; what is there must read);
- wrong verdict: exit status or verdict line other than expected.

Bounds (configured timeouts: connect C, reply R, shutdown S, stall limit L, grace G; the run
time T: the longest undisturbed run), each "2 x the relevant timeout + grace":

    SIGKILL/SIGTERM of a solver   2 G + G              the coupler's time to notice, the stop
    SIGSTOP of a solver           2 max(C, R, S) + G   the coupler's timeout names it
    SIGKILL of the coupler        2 G + G
    SIGTERM of the coupler        2 max(S, G) + G      its SHUTDOWN to both solvers
    SIGSTOP of the coupler        2 L + G              the stall limit
    SIGINT group, SIGTERM run_case.sh   2 (2 G + 1) + G   run_case.sh's wait for the coupler
    SIGSTOP of run_case.sh        2 T + G              from the resume
    SIGKILL of run_case.sh        2 (T + R) + G        until no orphan is left

The plan (class and moment as a fraction of the run time of every trial) follows from the
seed; the timing of the machine does not. --only limits the plan to some classes (to repeat
a finding). --keep keeps the folders of failed trials (run_case.out: run_case.sh's output;
run/: the run with its logs).

Exit status 0 when no trial hung, was late, left a process, left an unreadable file or got a
wrong verdict; 1 otherwise; 2 when the undisturbed run does not succeed; 130 on Ctrl-C or
SIGTERM (the running trials are killed).
"""
import argparse
import concurrent.futures
import os
import random
import re
import shutil
import signal
import statistics
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests"))
import h5py  # noqa: E402
from xdmf_check import check_xdmf  # noqa: E402

TIMEOUTS_S = {"connect": 4, "reply": 4, "shutdown": 2}
STALL_S = 6
GRACE_S = 3
HANG_EXTRA_S = 60
POLL_S = 0.02
VICTIMS = ("fem_solver", "dem_solver", "coupler", "run_case.sh")
CLASSES = [(f, v) for f in ("SIGKILL", "SIGTERM", "SIGSTOP") for v in VICTIMS] + \
          [("SIGINT", "group")]
H5_FILES = ("fem.h5", "dem.h5", "coupling.h5")
XDMF_FILES = (("fem.xdmf", "/output/time"), ("particles.xdmf", "/time"),
              ("dem_net.xdmf", "/time"))

# EXPECTED[(fault, victim)]: run_case.sh's exit status and its verdict line
FAILED = r"^run_case: failed: %s \("
EXPECTED = {}
for _f in ("SIGKILL", "SIGTERM", "SIGSTOP"):
    for _v, _name in (("fem_solver", "fem"), ("dem_solver", "dem")):
        EXPECTED[(_f, _v)] = (1, FAILED % _name)
EXPECTED[("SIGKILL", "coupler")] = (1, FAILED % "coupler" + r"exit 137 = SIGKILL")
EXPECTED[("SIGTERM", "coupler")] = (130, r"^run_case: stopped by user \(SIGTERM\)")
EXPECTED[("SIGSTOP", "coupler")] = (1, FAILED % "coupler" + r"stalled: ")
EXPECTED[("SIGINT", "group")] = (130, r"^run_case: stopped by user \(SIGINT\)")
EXPECTED[("SIGTERM", "run_case.sh")] = (130, r"^run_case: stopped by user \(SIGTERM\)")
EXPECTED[("SIGSTOP", "run_case.sh")] = (0, r"^run_case: done")
EXPECTED[("SIGKILL", "run_case.sh")] = (-9, None)   # no verdict; the orphans are checked
DONE = (0, r"^run_case: done")
VERDICT = re.compile(r"^run_case: (failed|stopped by user|done|finished)")


def bound_s(fault, victim, run_s):
    g, r = GRACE_S, TIMEOUTS_S["reply"]
    if victim in ("fem_solver", "dem_solver"):
        return 2 * max(TIMEOUTS_S.values()) + g if fault == "SIGSTOP" else 3 * g
    if victim == "coupler":
        return {"SIGKILL": 3 * g, "SIGTERM": 2 * max(TIMEOUTS_S["shutdown"], g) + g,
                "SIGSTOP": 2 * STALL_S + g}[fault]
    if fault == "SIGSTOP":
        return 2 * run_s + g
    if fault == "SIGKILL":
        return 2 * (run_s + r) + g
    return 2 * (2 * g + 1) + g


# ---- processes of a trial --------------------------------------------------------------
def trial_processes(marker):
    """[(pid, comm, state, ppid)] of the live processes whose environment holds marker."""
    found = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open("/proc/%s/environ" % d, "rb") as f:
                if marker not in f.read().split(b"\0"):
                    continue
            with open("/proc/%s/stat" % d) as f:
                stat = f.read()
        except OSError:
            continue
        comm = stat[stat.index("(") + 1:stat.rindex(")")]
        state, ppid = stat[stat.rindex(")") + 2:].split()[:2]
        if state != "Z":
            found.append((int(d), comm, state, int(ppid)))
    return found


def kill_all(marker, proc):
    if proc.poll() is None:   # (once reaped, its number may belong to someone else)
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except OSError:
            pass
    for pid, _, _, _ in trial_processes(marker):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def alive(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            stat = f.read()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


def coupler_state(run):
    try:
        with open(os.path.join(run, "coupler.progress")) as f:
            for line in f:
                if line.startswith("state "):
                    return line.split(None, 1)[1].strip()
    except OSError:
        pass
    return "coupler start-up"   # before its signal handler and first progress file


# ---- files -----------------------------------------------------------------------------
def unreadable_files(run):
    problems = []
    for name in H5_FILES:
        path = os.path.join(run, name)
        if not os.path.exists(path):
            continue
        try:
            with h5py.File(path, "r") as f:
                def read(_, obj):
                    if isinstance(obj, h5py.Dataset):
                        obj[()]
                f.visititems(read)
        except Exception as e:   # noqa: BLE001 (any failure to read is the finding)
            problems.append("%s: %s" % (name, e))
    for name, times in XDMF_FILES:
        path = os.path.join(run, name)
        if not os.path.exists(path):
            continue
        try:
            found = check_xdmf(path, times)
        except Exception as e:   # noqa: BLE001
            found = ["%s: %s" % (type(e).__name__, e)]
        if found:
            more = " (+%d more)" % (len(found) - 1) if len(found) > 1 else ""
            problems.append("%s: %s%s" % (name, found[0], more))
    return problems


# ---- one trial -------------------------------------------------------------------------
class Trial:
    def __init__(self, index, fault, victim, fraction):
        self.index, self.fault, self.victim, self.fraction = index, fault, victim, fraction
        self.folder = ""
        self.moment_s = None      # when the fault was sent, from the start of run_case.sh
        self.phase = ""           # start-up, connecting, running, finishing, stopping, ended
        self.missed = False
        self.rc = None
        self.latency_s = None
        self.bound_s = 0.0
        self.verdict = ""
        self.problems = {}        # kind -> text
        self.note = ""
        self.attempts = 1
        self.exit_s = None        # when run_case.sh ended, from its start

    @property
    def name(self):
        return "%s %s" % (self.fault, self.victim)

    def failed(self):
        return bool(self.problems)


class Soak:
    def __init__(self, args):
        self.args = args
        self.stop = threading.Event()
        self.active = {}          # pid -> (Popen, marker) of the running trials
        self.lock = threading.Lock()
        self.run_s = self.run_max_s = 0.0

    def start(self, folder):
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        env = dict(os.environ, NC_BIN=self.args.bin, NC_STALL_LIMIT_S=str(STALL_S),
                   NC_ENDPOINT_WAIT_S=str(STALL_S),
                   NC_STOP_GRACE_S=str(GRACE_S), OMP_NUM_THREADS="1",
                   NC_SOAK_TRIAL=folder)
        cmd = [os.path.join(ROOT, "scripts", "run_case.sh"), self.args.case,
               "--out", os.path.join(folder, "run")]
        for key, value in TIMEOUTS_S.items():
            cmd += ["--set", "coupler.timeouts.%s=%s" % (key, value)]
        out = open(os.path.join(folder, "run_case.out"), "w")
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                env=env, cwd=ROOT, start_new_session=True)
        out.close()
        marker = ("NC_SOAK_TRIAL=" + folder).encode()
        with self.lock:
            self.active[proc.pid] = (proc, marker)
        return proc, marker, time.monotonic()

    def finish(self, proc, marker):
        kill_all(marker, proc)
        proc.wait()
        until = time.monotonic() + 10   # SIGKILL takes effect asynchronously: wait for it
        while trial_processes(marker) and time.monotonic() < until:
            kill_all(marker, proc)
            time.sleep(0.05)
        with self.lock:
            self.active.pop(proc.pid, None)

    def wait_exit(self, proc, until):
        while proc.poll() is None and time.monotonic() < until and not self.stop.is_set():
            time.sleep(POLL_S)
        return proc.poll()

    def calibrate(self):
        """Runs the case undisturbed (jobs at a time, as the trials): its wall time is T."""
        def one(i):
            folder = os.path.join(self.args.dir, "undisturbed-%d" % i)
            proc, marker, t0 = self.start(folder)
            rc = self.wait_exit(proc, t0 + 300)
            took = time.monotonic() - t0
            self.finish(proc, marker)
            with open(os.path.join(folder, "run_case.out")) as f:
                text = f.read()
            bad = unreadable_files(os.path.join(folder, "run"))
            if rc != 0 or bad:
                sys.exit("soak: the undisturbed run did not succeed (exit %s%s); see %s\n%s"
                         % (rc, ", " + bad[0] if bad else "", folder, text[-2000:]))
            shutil.rmtree(folder, ignore_errors=True)
            return took
        with concurrent.futures.ThreadPoolExecutor(self.args.jobs) as pool:
            times = list(pool.map(one, range(self.args.jobs)))
        # the moments: the shortest (a longer one would leave many faults after the end);
        # the bounds that include the run time: the longest
        self.run_s, self.run_max_s = min(times), max(times)
        return times

    def trial(self, plan):
        """One trial of the plan; a fault that missed its victim (the run ended first, which
        under a varying load is frequent) is tried again, at most twice, at the same fraction
        of the run time that missed run took."""
        run_s = self.run_s
        for attempt in range(1, 4):
            t = Trial(plan.index, plan.fault, plan.victim, plan.fraction)
            t.attempts = attempt
            self.attempt(t, run_s)
            if self.stop.is_set() or not t.missed or t.failed() or t.exit_s is None:
                break
            run_s = t.exit_s
        return t

    def attempt(self, t, run_s):
        t.folder = os.path.join(self.args.dir, "trial-%03d" % t.index)
        run = os.path.join(t.folder, "run")
        t.bound_s = bound_s(t.fault, t.victim, self.run_max_s)
        proc, marker, t0 = self.start(t.folder)
        try:
            self.hit(t, proc, marker, t0, run, run_s)
            if not self.stop.is_set():
                self.judge(t, proc, marker, run, t0)
        finally:
            self.finish(proc, marker)
        if self.stop.is_set():
            return
        bad = unreadable_files(run)
        if bad:
            t.problems["unreadable"] = "; ".join(bad)
        if not t.failed() or not self.args.keep:
            shutil.rmtree(t.folder, ignore_errors=True)

    def hit(self, t, proc, marker, t0, run, run_s):
        """Sends the fault at t0 + fraction x run_s (or when the victim appears)."""
        moment = t0 + t.fraction * run_s
        seen = {}    # comm -> pid of the programs seen so far
        while not self.stop.is_set():
            ended = proc.poll() is not None
            now = time.monotonic()
            if now >= moment or ended:
                for pid, comm, _, ppid in ([] if ended else trial_processes(marker)):
                    if ppid == proc.pid and comm in VICTIMS[:3]:
                        seen.setdefault(comm, pid)
                exists = lambda name: os.path.exists(os.path.join(run, name))  # noqa: E731
                if "coupler" in seen and alive(seen["coupler"]):
                    phase = coupler_state(run)
                elif exists("coupler.progress"):   # written by the coupler itself
                    phase = "ended"
                else:
                    phase = "start-up"
                if t.victim in ("run_case.sh", "group"):
                    pid = proc.pid
                else:
                    pid = seen.get(t.victim)
                    # an endpoint file, a progress file: written by the program itself
                    gone = exists({"fem_solver": "fem.endpoint", "dem_solver": "dem.endpoint",
                                   "coupler": "coupler.progress"}[t.victim])
                    if pid is None and not ended and not gone:
                        time.sleep(POLL_S)   # not started yet: hit it when it appears
                        continue
                t.phase = "ended" if ended else phase
                t.moment_s = now - t0
                if ended or pid is None or not alive(pid):
                    t.missed = True
                    return
                sig = getattr(signal, t.fault)
                if t.victim == "group":
                    os.killpg(proc.pid, sig)
                else:
                    os.kill(pid, sig)
                return
            time.sleep(min(POLL_S, moment - now))

    def judge(self, t, proc, marker, run, start):
        sent = t0 = time.monotonic()
        if t.fault == "SIGSTOP" and t.victim == "run_case.sh" and not t.missed:
            # a stopped supervisor reports nothing: resume it after the stall limit
            self.wait_exit(proc, sent + STALL_S)
            if proc.poll() is None:
                os.kill(proc.pid, signal.SIGCONT)
            t0 = time.monotonic()
        rc = self.wait_exit(proc, t0 + t.bound_s + HANG_EXTRA_S)
        if self.stop.is_set():
            return
        end = time.monotonic()
        if rc is None:
            t.problems["hang"] = "run_case.sh still running %.0f s after the fault (bound %.0f s)" \
                % (end - sent, t.bound_s)
            t.note = "; ".join("%d %s (%s)" % (p, c, s) for p, c, s, _ in trial_processes(marker))
            return
        t.rc = rc
        t.latency_s = end - t0
        t.exit_s = end - start
        if t.fault == "SIGKILL" and t.victim == "run_case.sh" and not t.missed:
            t.latency_s = None
            # the orphans carry on: the coupler finishes the run and shuts the solvers down
            until = sent + t.bound_s
            while trial_processes(marker) and time.monotonic() < until:
                time.sleep(0.2)
            left = trial_processes(marker)
            t.note = "orphans ended after %.1f s" % (time.monotonic() - sent) if not left else ""
        else:
            if t.latency_s > t.bound_s:
                t.problems["late"] = "stopped after %.1f s, bound %.0f s" % (t.latency_s, t.bound_s)
            time.sleep(0.2)
            left = trial_processes(marker)
        if left:
            t.problems["leftover"] = ", ".join("%d %s (state %s)" % (p, c, s)
                                               for p, c, s, _ in left)
        with open(os.path.join(t.folder, "run_case.out"), errors="replace") as f:
            lines = [ln.rstrip("\n") for ln in f if VERDICT.match(ln)]
        t.verdict = lines[0] if lines else ""
        self.check_verdict(t, run)

    def check_verdict(self, t, run):
        expected = [DONE] if t.missed else [EXPECTED[(t.fault, t.victim)]]
        if not t.missed and t.phase in ("finishing", "ended") and t.fault != "SIGSTOP" \
                and not (t.fault == "SIGKILL" and t.victim in ("coupler", "run_case.sh")):
            # the run is complete: the signal may come after the victim's clean exit, or
            # while it shuts down anyway
            expected.append(DONE)
        if t.fault in ("SIGINT", "SIGTERM") and t.victim in ("group", "run_case.sh") \
                and not os.path.exists(os.path.join(run, "fem.log")):
            # before run_case.sh set its traps (copying the case, --set): the signal ends it,
            # nothing had been started
            expected.append((-getattr(signal, t.fault), None))
        if t.fault == "SIGTERM" and t.victim == "coupler" and t.phase == "coupler start-up":
            # before the coupler installed its handler the signal ends it (the default action)
            expected.append((1, FAILED % "coupler" + r"exit 143 = SIGTERM"))
        for rc, pattern in expected:
            if t.rc == rc and (pattern is None or re.match(pattern, t.verdict)):
                return
        want = " or ".join("exit %d%s" % (rc, ", '%s'" % p.lstrip("^").replace("\\", "")
                                          if p else "") for rc, p in expected)
        t.problems["verdict"] = "exit %s, '%s'; expected %s" % (t.rc, t.verdict, want)

    def kill_active(self):
        with self.lock:
            for proc, marker in list(self.active.values()):
                kill_all(marker, proc)


# ---- report ----------------------------------------------------------------------------
KINDS = ("hang", "late", "leftover", "unreadable", "verdict")


def describe(t):
    when = "at %.2f s (%s)" % (t.moment_s, t.phase) if t.moment_s is not None else ""
    head = "trial %d: %s %s%s" % (t.index, t.name, when,
                                  ", missed: the victim had ended" if t.missed else "")
    if t.rc is not None:
        head += "; run_case.sh exit %d" % t.rc
        if t.latency_s is not None:
            head += " after %.1f s (bound %.0f s)" % (t.latency_s, t.bound_s)
    lines = [head]
    for kind in KINDS:
        if kind in t.problems:
            lines.append("    %s: %s" % (kind, t.problems[kind]))
    if t.verdict and "verdict" not in t.problems:
        lines.append("    verdict: %s" % t.verdict)
    if t.note:
        lines.append("    note: %s" % t.note)
    return "\n".join(lines)


def table(trials):
    print("%-22s %6s %6s %6s %5s %5s %8s %10s %7s %15s %6s"
          % ("class", "trials", "missed", "ok", "hang", "late", "leftover", "unreadable",
             "verdict", "latency med/max", "bound"))
    for fault, victim in CLASSES:
        ts = [t for t in trials if (t.fault, t.victim) == (fault, victim)]
        if not ts:
            continue
        lat = [t.latency_s for t in ts if t.latency_s is not None]
        count = {k: sum(k in t.problems for t in ts) for k in KINDS}
        lat_text = "%.1f/%.1f s" % (statistics.median(lat), max(lat)) if lat else "-"
        print("%-22s %6d %6d %6d %5d %5d %8d %10d %7d %15s %5.0fs"
              % ("%s %s" % (fault, victim), len(ts), sum(t.missed for t in ts),
                 sum(not t.failed() for t in ts), count["hang"], count["late"],
                 count["leftover"], count["unreadable"], count["verdict"], lat_text,
                 ts[0].bound_s))
    return {k: sum(k in t.problems for t in trials) for k in KINDS}


def on_terminate(*_):
    raise KeyboardInterrupt


def main():
    ap = argparse.ArgumentParser(description="kill and stall trials of scripts/run_case.sh "
                                 "(see the header of this file)")
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--seed", type=int, default=None, help="default: a random one, printed")
    ap.add_argument("--jobs", type=int, default=2, help="trials at a time (default 2)")
    ap.add_argument("--keep", action="store_true", help="keep the folders of failed trials")
    ap.add_argument("--only", action="append", metavar="FAULT:VICTIM",
                    help="only these classes, e.g. SIGSTOP:coupler, SIGINT:group (repeatable)")
    ap.add_argument("--case", default=os.path.join(ROOT, "tests/coupler/cases/small_net"))
    ap.add_argument("--dir", default=os.path.join(ROOT, "build/soak"),
                    help="where the trial folders go (default build/soak)")
    ap.add_argument("--bin", default=os.path.join(ROOT, "bin"), help="the programs (NC_BIN)")
    args = ap.parse_args()
    if args.trials < 1 or args.jobs < 1:
        ap.error("--trials and --jobs must be at least 1")
    args.dir, args.bin, args.case = (os.path.abspath(p) for p in (args.dir, args.bin, args.case))
    for p in ("fem_solver", "dem_solver", "coupler"):
        if not os.access(os.path.join(args.bin, p), os.X_OK):
            sys.exit("soak: %s/%s not found (build with make)" % (args.bin, p))
    classes = CLASSES
    if args.only:
        classes = [c for c in CLASSES if "%s:%s" % c in args.only]
        unknown = set(args.only) - {"%s:%s" % c for c in CLASSES}
        if unknown:
            ap.error("--only %s: classes are %s" % (", ".join(sorted(unknown)),
                                                   ", ".join("%s:%s" % c for c in CLASSES)))
    seed = args.seed if args.seed is not None else random.SystemRandom().randrange(1, 10**6)
    rng = random.Random(seed)
    plan = [Trial(i + 1, *rng.choice(classes), rng.random()) for i in range(args.trials)]
    os.makedirs(args.dir, exist_ok=True)
    for name in os.listdir(args.dir):   # the failed trials of an earlier soak
        if name.startswith(("trial-", "undisturbed-")):
            shutil.rmtree(os.path.join(args.dir, name), ignore_errors=True)

    # a handler, not an inherited SIG_IGN (as for a background job of a script): the trials
    # start with the default dispositions, and run_case.sh can trap SIGINT
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, on_terminate)
    soak = Soak(args)
    print("soak: %d trials, seed %d (SOAK_SEED=%d repeats the plan), %d at a time, in %s"
          % (args.trials, seed, seed, args.jobs, args.dir))
    print("soak: timeouts connect %d s, reply %d s, shutdown %d s (coupler.json), stall limit "
          "%d s, grace %d s, the solvers' idle timeout their default (run_case.sh passes none)"
          % (TIMEOUTS_S["connect"], TIMEOUTS_S["reply"], TIMEOUTS_S["shutdown"], STALL_S, GRACE_S))
    done = []
    pool = concurrent.futures.ThreadPoolExecutor(args.jobs)
    try:
        times = soak.calibrate()
        print("soak: undisturbed run %s s: faults uniform over 0..%.2f s, T = %.2f s in the bounds"
              % ("/".join("%.2f" % x for x in times), soak.run_s, soak.run_max_s))
        futures = [pool.submit(soak.trial, t) for t in plan]
        for fut in concurrent.futures.as_completed(futures):
            t = fut.result()
            done.append(t)
            status = ", ".join(sorted(t.problems)) if t.failed() else \
                ("ok (missed)" if t.missed else "ok")
            lat = "%.1f s" % t.latency_s if t.latency_s is not None else t.note or "-"
            again = " (try %d)" % t.attempts if t.attempts > 1 else ""
            print("  %3d/%d trial %3d %-20s at %5.2f s%s (%s): exit %s, %s: %s"
                  % (len(done), args.trials, t.index, t.name, t.moment_s or 0, again, t.phase,
                     t.rc, lat, status), flush=True)
    except KeyboardInterrupt:
        soak.stop.set()
        pool.shutdown(wait=False, cancel_futures=True)
        soak.kill_active()
        print("soak: stopped by user after %d trials" % len(done))
        return 130
    pool.shutdown()
    done.sort(key=lambda t: t.index)
    print()
    count = table(done)
    failed = [t for t in done if t.failed()]
    if failed:
        print()
        for t in failed:
            print(describe(t))
            if args.keep:
                print("    folder: %s" % t.folder)
    over = [t.latency_s / t.bound_s for t in done if t.latency_s is not None]
    print()
    print("soak: %d trials (seed %d): %d hangs, %d leftovers, %d unreadable files, %d wrong "
          "verdicts, %d over the latency bound (largest latency/bound %.2f); %d faults missed "
          "their victim (%d trials repeated after a miss)"
          % (len(done), seed, count["hang"], count["leftover"], count["unreadable"],
             count["verdict"], count["late"], max(over) if over else 0,
             sum(t.missed for t in done), sum(t.attempts > 1 for t in done)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
