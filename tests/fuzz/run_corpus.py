#!/usr/bin/python3
"""Runs the fuzz corpus of bad inputs (tests/fuzz/corpus.tsv, made by make_corpus.py) against pfflip.

    /usr/bin/python3 tests/fuzz/run_corpus.py PFFLIP MPIEXEC CORPUS [--jobs 2] [--filter REGEX] [--report out.csv]

PFFLIP   the binary (run from a copy in the scratch directory, so that a rebuild cannot replace it mid-run)
MPIEXEC  the launcher and its flags as one shell-quoted string, e.g. "mpiexec --oversubscribe --bind-to none"
CORPUS   the corpus file

Every case runs at each of its rank counts, with a time-out (default 20 s; the whole process group is killed).
Each run falls in one class:
  clean      exit status 1, exactly one line "pfflip: error: ..." containing the case's expect string, no
             traceback or abort banner, nothing written to -output_dir: what the case asks for
  accepted   exit status 0: the bad input was accepted and the run went on
  traceback  a PETSc traceback (PETSC ERROR), an MPI_ABORT / MPI_Abort banner or a Python Traceback
  other      any other failure: a signal, an exit status other than 1, no or several error lines (or one of
             the form "pfflip: error on rank N:"), an error line that does not name the key or file, or a
             -output_dir created by the failed run
  hang       no exit within the time-out
Prints a line per run that is not clean (id@npN, class, what was wrong, what it printed) and a summary with the
class counts and the wall time; exits with status 1 unless every run is clean.

Runs at 1 rank share the --jobs slots two at a time (default 2); a run at 2 ranks takes both. Runs at 1 rank
set OMPI_MCA_odls_base_sigkill_timeout=0: with no other rank left to stop, Open MPI's 2 s wait after a
non-zero exit only costs time. Each run gets an address-space limit (--mem-limit-mb, default 4096 per process;
0: none; off for sanitizer builds) so that a huge grid fails to allocate instead of exhausting the machine.
A run whose mpiexec failed before starting any rank (Open MPI's "ORTE_ERROR_LOG ... session_dir.c", two launches
of the parallel slots racing for one session directory; seen once in CI on 2026-12-03) is launched again once:
pfflip never ran, so its result says nothing about the input.
"""
import argparse
import csv
import hashlib
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CLASSES = ("clean", "accepted", "traceback", "other", "hang")
# the output of an mpiexec whose launcher failed before starting the ranks
LAUNCH_FAILURE = re.compile(r"ORTE_ERROR_LOG: Error in file .*session_dir\.c")
FORBID = re.compile(r"PETSC ERROR|MPI_ABORT|MPI_Abort|Traceback")
ERROR_LINE = re.compile(r"pfflip: error")
SIGNAL = re.compile(r"exited on signal|Caught signal|Segmentation fault|Aborted \(core dumped\)|Killed")


# ---- files the cases need ------------------------------------------------------------------
# YAML generators: a bad scene file from the text of the case's scene; the file replaces the scene as
# -options_file_yaml and is named <generator>.yaml. Each is deterministic.
def _lines(text):
    return text.split("\n")


def _first_scalar(lines, top_level=True):
    """Index of the first 'key: value' line (top-level if asked), value not a flow map."""
    for i, line in enumerate(lines):
        m = re.match(r"^(\s*)([A-Za-z0-9_]+):\s+([^{#\s][^#]*)$", line)
        if m and (not top_level or not m.group(1)):
            return i, m
    raise ValueError("no scalar line")


def _first_indented(lines):
    for i, line in enumerate(lines):
        if re.match(r"^ +[A-Za-z0-9_]+:", line):
            return i
    raise ValueError("no indented line")


def gen_unclosed_quote(text):
    lines = _lines(text)
    for i, line in enumerate(lines):
        if line.count('"') >= 2 and not line.lstrip().startswith("#"):
            j = line.index('"', line.index('"') + 1)
            lines[i] = line[:j] + line[j + 1:]
            return "\n".join(lines)
    i, m = _first_scalar(lines, top_level=False)
    lines[i] = f'{m.group(1)}{m.group(2)}: "{m.group(3).rstrip()}'
    return "\n".join(lines)


def gen_unclosed_brace(text):
    if "}" in text:
        i = text.index("}")
        return text[:i] + text[i + 1:]
    return text + 'liquid_9: {type: box, lo: "0,0,0"\n'


def gen_tab_indent(text):
    lines = _lines(text)
    i = _first_indented(lines)
    lines[i] = "\t" + lines[i].lstrip(" ")
    return "\n".join(lines)


def gen_bad_indent(text):
    lines = _lines(text)
    i = _first_indented(lines)
    lines.insert(i + 1, " " + lines[i].lstrip(" ").split(":")[0] + "_x: 1")
    return "\n".join(lines)


def gen_truncated(text):
    """Cut in the middle of a key, as an interrupted copy would: the last key that has an earlier sibling in
    its mapping, so that the cut key cannot pass for the value of its parent."""
    lines = _lines(text.rstrip("\n"))
    keys = [(i, m) for i, m in ((i, re.match(r"^( *)([A-Za-z0-9_]+):", l)) for i, l in enumerate(lines)) if m]
    for n in range(len(keys) - 1, 0, -1):
        i, m = keys[n]
        d = len(m.group(1))
        for k in range(n - 1, -1, -1):
            dk = len(keys[k][1].group(1))
            if dk < d:
                break
            if dk == d and len(m.group(2)) >= 2:
                return "\n".join(lines[:i] + [m.group(1) + m.group(2)[: len(m.group(2)) // 2 + 1]])
    return text[: len(text) // 2]


def gen_top_level_list(text):
    items = []
    for line in _lines(text):
        m = re.match(r"^([A-Za-z0-9_]+):\s+([^{#\s][^#]*)$", line)
        if m:
            items.append(f"- {m.group(1)}: {m.group(2).strip()}")
    return "\n".join(items) + "\n"


def gen_top_level_scalar(text):
    _, m = _first_scalar(_lines(text))
    return m.group(3).strip() + "\n"


def gen_deep_nesting(text):
    out = [f"{'  ' * d}n{d:02d}:" for d in range(29)]
    out.append(f"{'  ' * 29}n29: 1")
    return text.rstrip("\n") + "\n" + "\n".join(out) + "\n"


def _garbage(n, seed=b"pfflip-fuzz"):
    data, block = b"", seed
    while len(data) < n:
        block = hashlib.sha256(block).digest()
        data += block
    return data[:n]


def gen_binary_garbage(text):
    return _garbage(1024)


def gen_nul_byte(text, insert="\0"):
    """A NUL in the middle of the first top-level value (scene: fl\\0uid)."""
    lines = _lines(text)
    i, m = _first_scalar(lines)
    v = m.group(3).rstrip()
    lines[i] = f"{m.group(2)}: {v[: len(v) // 2]}{insert}{v[len(v) // 2:]}"
    return "\n".join(lines)


def gen_empty(text):
    return ""


def gen_invalid_utf8(text):
    """Bytes 0xff 0xfe (never valid UTF-8) in the middle of the first top-level value."""
    return gen_nul_byte(text, "\udcff\udcfe")


def gen_undefined_alias(text):
    return _set_top(text, "rho_gas", "*nosuch")


def gen_yaml_directive(text):
    return "%YAML 9.9\n---\n" + text


def gen_long_key(text):
    return text.rstrip("\n") + "\n" + "k" * 5000 + ": 1\n"


def gen_long_value(text):
    lines = _lines(text)
    i, m = _first_scalar(lines)
    lines[i] = f"{m.group(2)}: " + "x" * 100000
    return "\n".join(lines)


def gen_duplicate_key(text):
    return text.rstrip("\n") + "\nrho_gas: 2\n"


def gen_mapping_as_value(text):
    return _set_top(text, "rho_gas", "{a: 1}")


def gen_list_as_value(text):
    return _set_top(text, "rho_gas", "[1, 2]")


def gen_null_value(text):
    return _set_top(text, "rho_gas", "")


def _set_top(text, key, value):
    lines = _lines(text)
    for i, line in enumerate(lines):
        if re.match(rf"^{key}:", line):
            lines[i] = f"{key}: {value}".rstrip()
            return "\n".join(lines)
    return text.rstrip("\n") + f"\n{key}: {value}".rstrip() + "\n"


def gen_misspelt_section(text, arg):
    """misspelt_section:SEC=BAD renames the section SEC: to BAD:."""
    sec, bad = arg.split("=", 1)
    new, n = re.subn(rf"(?m)^{re.escape(sec)}:", f"{bad}:", text)
    if not n:
        raise ValueError(f"no section {sec}:")
    return new


def gen_set(text, arg):
    """set:KEY=VALUE or set:SECTION.KEY=VALUE: the scene with that value (in a block section, a flow map or at
    the top level), added if the scene lacks it."""
    path, value = arg.split("=", 1)
    if "." not in path:
        return _set_top(text, path, value)
    sec, key = path.split(".", 1)
    lines = _lines(text)
    for i, line in enumerate(lines):
        if re.match(rf"^{re.escape(sec)}:\s*\{{", line):  # flow map
            new, n = re.subn(rf'(\b{re.escape(key)}:\s*)("[^"]*"|[^,}}]+)', rf'\g<1>"{value}"', line)
            lines[i] = new if n else line.replace("{", f'{{{key}: "{value}", ', 1)
            return "\n".join(lines)
        if re.match(rf"^{re.escape(sec)}:\s*$", line):  # block section
            j = i + 1
            while j < len(lines) and re.match(r"^\s+\S", lines[j]):
                if re.match(rf"^\s+{re.escape(key)}:", lines[j]):
                    lines[j] = re.sub(rf"^(\s+{re.escape(key)}:).*$", rf"\g<1> {value}", lines[j])
                    return "\n".join(lines)
                j += 1
            lines.insert(i + 1, f"  {key}: {value}")
            return "\n".join(lines)
    return text.rstrip("\n") + f"\n{sec}:\n  {key}: {value}\n"


YAML_GENERATORS = {
    "unclosed_quote": gen_unclosed_quote, "unclosed_brace": gen_unclosed_brace, "tab_indent": gen_tab_indent,
    "bad_indent": gen_bad_indent, "truncated": gen_truncated, "top_level_list": gen_top_level_list,
    "top_level_scalar": gen_top_level_scalar, "deep_nesting": gen_deep_nesting,
    "binary_garbage": gen_binary_garbage, "nul_byte": gen_nul_byte, "empty": gen_empty,
    "invalid_utf8": gen_invalid_utf8, "undefined_alias": gen_undefined_alias, "yaml_directive": gen_yaml_directive,
    "long_key": gen_long_key, "long_value": gen_long_value, "duplicate_key": gen_duplicate_key,
    "mapping_as_value": gen_mapping_as_value, "list_as_value": gen_list_as_value, "null_value": gen_null_value,
    "misspelt_section": gen_misspelt_section, "set": gen_set,
}
# Other files, given to the case as {file}: name -> (file name, content or the fixture file it copies).
FILE_GENERATORS = {
    "text_file": ("plain.txt", b"this is a text file, not a checkpoint or a directory\n"),
    "directory": ("a_directory", None),
    "empty_file": ("empty.h5", b""),
    "fake_hdf5": ("fake.h5", b"\x89HDF\r\n\x1a\n" + _garbage(4096, b"hdf5")),
    "binary_garbage_file": ("garbage.bin", _garbage(1024)),
    "checkpoint": ("checkpoint.h5", ("fixture", "checkpoint.h5", None)),
    "checkpoint_truncated": ("truncated_checkpoint.h5", ("fixture", "checkpoint.h5", 0.5)),
    "frame": ("frame_0000.h5", ("fixture", "frame_0000.h5", None)),
}
FIXTURE_SPECS = {k for k, v in FILE_GENERATORS.items() if isinstance(v[1], tuple)}


def make_file(spec, scene_text, tmp, fixture_dir):
    """Writes the file of yaml_spec into tmp; returns (path, is_yaml_scene)."""
    name, _, arg = spec.partition(":")
    if name in YAML_GENERATORS:
        gen = YAML_GENERATORS[name]
        data = gen(scene_text, arg) if arg else gen(scene_text)
        path = os.path.join(tmp, f"{name}.yaml")
        with open(path, "wb") as f:
            f.write(data.encode("utf-8", "surrogateescape") if isinstance(data, str) else data)
        return path, True
    if name in FILE_GENERATORS:
        fname, content = FILE_GENERATORS[name]
        path = os.path.join(tmp, fname)
        if content is None:
            os.makedirs(path)
            return path, False
        if isinstance(content, tuple):
            _, src, share = content
            with open(os.path.join(fixture_dir, src), "rb") as f:
                data = f.read()
            content = data[: int(len(data) * share)] if share else data
        with open(path, "wb") as f:
            f.write(content)
        return path, False
    raise ValueError(f"unknown yaml_spec {spec!r}")


# ---- running ---------------------------------------------------------------------------------
def read_corpus(path):
    cases, header = [], None
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line or line.startswith("#"):
                continue
            cols = line.split("\t")
            if header is None:
                header = cols
                continue
            if len(cols) != len(header):
                raise SystemExit(f"run_corpus.py: {path}:{n}: {len(cols)} columns, expected {len(header)}")
            cases.append(dict(zip(header, cols)))
    return cases


class Runner:
    def __init__(self, a):
        self.a = a
        self.launcher = shlex.split(a.mpiexec)
        self.env = dict(os.environ)
        for k, v in (("OMPI_ALLOW_RUN_AS_ROOT", "1"), ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
                     ("OMP_NUM_THREADS", "1"), ("OMPI_MCA_rmaps_base_oversubscribe", "1")):
            self.env.setdefault(k, v)
        self.mem_kb = a.mem_limit_mb * 1024 if a.mem_limit_mb > 0 and not self.sanitized(a.pfflip) else 0
        self.lock = threading.Condition()
        self.free = a.jobs
        self.results = []
        self.fixture_dir = os.path.join(a.workdir, "fixture")
        self.fixture_error = None

    @staticmethod
    def sanitized(exe):
        try:
            with open(exe, "rb") as f:
                return b"__asan_init" in f.read()
        except OSError:
            return False

    def command(self, np, args, extra_env=None):
        cmd = self.launcher + [self.a.np_flag, str(np), self.a.pfflip] + args
        if self.mem_kb:
            cmd = ["/bin/sh", "-c", 'ulimit -v "$0" 2>/dev/null; exec "$@"', str(self.mem_kb)] + cmd
        env = dict(self.env)
        env.update(extra_env or {})
        return cmd, env

    def execute(self, cmd, env, timeout):
        """Runs cmd in its own process group; returns (rc or None on time-out, output, seconds)."""
        token = f"{os.getpid()}-{threading.get_ident()}-{time.monotonic_ns()}"
        env = dict(env, PFF_FUZZ_TOKEN=token)
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env,
                             start_new_session=True)
        try:
            out, _ = p.communicate(timeout=timeout)
            rc = p.returncode
        except subprocess.TimeoutExpired:
            rc = None
            self.kill(p, token)
            try:
                out, _ = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                out = b""
        return rc, out.decode("utf-8", "replace"), time.monotonic() - t0

    @staticmethod
    def kill(p, token):
        """Kills the run's process group, then any process of the run that left it (found by its token)."""
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        needle = f"PFF_FUZZ_TOKEN={token}".encode()
        for pid in os.listdir("/proc"):
            if not pid.isdigit():
                continue
            try:
                with open(f"/proc/{pid}/environ", "rb") as f:
                    if needle in f.read().split(b"\0"):
                        os.kill(int(pid), signal.SIGKILL)
            except (OSError, ProcessLookupError):
                pass

    def make_fixture(self):
        """A dam-break checkpoint and frame after one step, for the restart cases."""
        out = self.fixture_dir
        args = ["-options_file_yaml", os.path.join(self.a.config_dir, "dam_break_small.yaml"), "-sim_max_steps", "1",
                "-sim_checkpoint_every", "1", "-output_dir", out]
        cmd, env = self.command(1, args)
        rc, text, _ = self.execute(cmd, env, 120)
        missing = [f for f in ("checkpoint.h5", "frame_0000.h5") if not os.path.isfile(os.path.join(out, f))]
        if rc != 0 or missing:
            self.fixture_error = f"fixture run failed (exit {rc}, missing {missing}): " + " | ".join(
                text.strip().splitlines()[-3:])

    def run_case(self, case, np):
        a = self.a
        cdir = os.path.join(a.workdir, "cases", f"{case['id']}@np{np}")
        shutil.rmtree(cdir, ignore_errors=True)
        os.makedirs(cdir)
        outdir = os.path.join(cdir, "out")
        res = {"id": case["id"], "np": np, "category": case.get("category", ""), "scene": case["scene"],
               "args": case["args"], "expect": case["expect"], "rc": "", "seconds": "", "class": "other",
               "detail": "", "error_lines": "", "output_head": ""}
        spec = case.get("yaml_spec", "")
        scene_path = os.path.join(a.config_dir, case["scene"]) if case["scene"] not in ("", "-") else None
        file_path, is_yaml = "", False
        if spec:
            if spec.partition(":")[0] in FIXTURE_SPECS and self.fixture_error:
                res["detail"] = self.fixture_error
                return res
            text = ""
            if scene_path:
                with open(scene_path, encoding="utf-8") as f:
                    text = f.read()
            try:
                file_path, is_yaml = make_file(spec, text, cdir, self.fixture_dir)
            except (ValueError, OSError) as e:
                res["detail"] = f"cannot make {spec}: {e}"
                return res
        subst = {"{out}": outdir, "{tmp}": cdir, "{file}": file_path, "{config}": a.config_dir}
        argstr = case["args"]
        for k, v in subst.items():
            argstr = argstr.replace(k, shlex.quote(v))
        args = shlex.split(argstr)
        if is_yaml:
            args = ["-options_file_yaml", file_path] + args
        elif scene_path:
            args = ["-options_file_yaml", scene_path] + args
        cmd, env = self.command(np, args, {"OMPI_MCA_odls_base_sigkill_timeout": "0"} if np == 1 else None)
        rc, text, secs = self.execute(cmd, env, a.timeout)
        if rc not in (None, 0) and LAUNCH_FAILURE.search(text):
            # Open MPI's launcher failed before any rank ran (two mpiexec of the parallel workers raced for one
            # session directory, "File exists"): nothing of pfflip was tested, so launch again once
            rc, text, secs = self.execute(cmd, env, a.timeout)
        res["rc"] = "timeout" if rc is None else rc
        res["seconds"] = f"{secs:.2f}"
        lines = text.splitlines()
        errs = [l for l in lines if ERROR_LINE.search(l)]
        res["error_lines"] = " || ".join(l[:300] for l in errs[:3])
        res["output_head"] = " || ".join(l[:300] for l in excerpt(lines, 4))
        expects = [e.strip() for e in case["expect"].split(" | ") if e.strip()]
        forbidden = [l for l in lines if FORBID.search(l)]
        if rc is None:
            res["class"], res["detail"] = "hang", f"no exit within {a.timeout:g} s"
        elif rc == 0:
            res["class"], res["detail"] = "accepted", "exit status 0"
        elif forbidden:
            telling = [l for l in forbidden if not PETSC_NOISE.search(l)] or forbidden
            res["class"], res["detail"] = "traceback", telling[0].strip()[:200]
        else:
            problems = []
            sig = [l for l in lines if SIGNAL.search(l)]
            if rc < 0 or rc > 128 or sig:  # mpiexec returns 128 + N for a rank killed by signal N
                problems.append("signal: " + (sig[0].strip()[:120] if sig else f"exit status {rc}"))
            elif rc != 1:
                problems.append(f"exit status {rc}")
            if len(errs) != 1:
                problems.append(f"{len(errs)} error lines")
            elif not errs[0].lstrip().startswith("pfflip: error:"):
                problems.append("error line not of the form 'pfflip: error: ...'")
            elif not any(e in errs[0] for e in expects):
                problems.append(f"error line does not name {' or '.join(expects)}")
            if os.path.exists(outdir):
                problems.append("created -output_dir")
            if problems:
                res["class"], res["detail"] = "other", "; ".join(problems)
            else:
                res["class"] = "clean"
        if res["class"] == "clean" and not a.keep:
            shutil.rmtree(cdir, ignore_errors=True)
        return res

    def worker(self, case, np, slots):
        try:
            res = self.run_case(case, np)
        except Exception as e:  # a bug of this script must not pass for a clean run
            res = {"id": case["id"], "np": np, "class": "other", "detail": f"run_corpus.py: {e!r}"}
        with self.lock:
            self.results.append(res)
            self.free += slots
            self.lock.notify_all()
            if res["class"] != "clean" or self.a.verbose:
                print(format_result(res), flush=True)

    def run(self, cases):
        tasks = [(c, int(n)) for c in cases for n in c["ranks"].split(",")]
        # multi-rank runs first: they need every slot, so they are not left to the end one by one
        tasks.sort(key=lambda t: -t[1])
        if any(c.get("yaml_spec", "").partition(":")[0] in FIXTURE_SPECS for c, _ in tasks):
            self.make_fixture()
        threads = []
        for case, np in tasks:
            slots = min(np, self.a.jobs)
            with self.lock:
                while self.free < slots:
                    self.lock.wait()
                self.free -= slots
            t = threading.Thread(target=self.worker, args=(case, np, slots))
            t.start()
            threads.append(t)
        for t in threads:
            t.join()
        order = {(c["id"], n): i for i, (c, n) in enumerate((c, int(n)) for c in cases for n in c["ranks"].split(","))}
        self.results.sort(key=lambda r: order.get((r["id"], r["np"]), 0))
        return self.results


PETSC_NOISE = re.compile(r"PETSC ERROR: (-{5}|See |Petsc Release|Configure options|WARNING! There are option|Option left|"
                         r".* on a .* named |Run with -malloc_debug|likely location|The EXACT line numbers|"
                         r"INSTEAD the line number|are not available,|Try option -start_in_debugger)")


def excerpt(lines, n):
    """The lines worth showing: pfflip's error lines, then PETSc's message and stack, abort banners and signals,
    then anything else; the first lines when none of these."""
    ranked = []
    for i, l in enumerate(lines):
        t = l.strip()
        if not t or re.match(r"^-+$", t):
            continue
        if ERROR_LINE.search(t):
            rank = 0
        elif "PETSC ERROR" in t and not PETSC_NOISE.search(t):
            rank = 1
        elif re.search(r"MPI_ABORT|MPI_Abort|signal|Traceback", t):
            rank = 2
        elif re.search(r"error", t, re.I):
            rank = 3
        else:
            continue
        ranked.append((rank, i, t))
    pick = [t for _, _, t in sorted(ranked)[:n]]
    return pick or [l.strip() for l in lines if l.strip()][:n]


def format_result(r):
    head = f"{r['class'].upper():9s} {r['id']}@np{r['np']}: {r.get('detail', '')}"
    shown = r.get("output_head", "")
    return head + (f"\n          :: {shown[:400]}" if shown and r["class"] != "clean" else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pfflip")
    ap.add_argument("mpiexec", help='launcher and flags, one shell-quoted string')
    ap.add_argument("corpus")
    ap.add_argument("--jobs", type=int, default=2, help="cores to use: runs at 1 rank in parallel (default 2)")
    ap.add_argument("--filter", default="", help="only the cases whose id matches this regex")
    ap.add_argument("--ranks", default="", help="only these rank counts, e.g. 1 or 2")
    ap.add_argument("--report", default="", help="write the per-run results to this CSV file")
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per run (default 20)")
    ap.add_argument("--np-flag", default="-n", help="the launcher's rank-count flag, as --np-flag=-n (the default)")
    ap.add_argument("--config-dir", default=os.path.join(ROOT, "config"), help="the shipped scenes")
    ap.add_argument("--workdir", default="", help="scratch directory (default: a new one in $TMPDIR, removed)")
    ap.add_argument("--keep", action="store_true", help="keep the directories of clean runs and the scratch directory")
    ap.add_argument("--mem-limit-mb", type=int, default=4096, help="address-space limit per process (0: none)")
    ap.add_argument("--no-copy", action="store_true", help="run PFFLIP in place (default: a copy in the workdir)")
    ap.add_argument("--verbose", action="store_true", help="print clean runs too")
    a = ap.parse_args()
    a.pfflip = os.path.abspath(a.pfflip)
    a.config_dir = os.path.abspath(a.config_dir)
    a.jobs = max(1, a.jobs)
    if not os.access(a.pfflip, os.X_OK):
        sys.exit(f"run_corpus.py: {a.pfflip} is not an executable")
    own_workdir = not a.workdir
    if own_workdir:
        a.workdir = tempfile.mkdtemp(prefix="pff-fuzz-")
    else:
        a.workdir = os.path.abspath(a.workdir)
        shutil.rmtree(a.workdir, ignore_errors=True)
        os.makedirs(a.workdir)
    if not a.no_copy:  # a rebuild during the run must not swap the binary under it
        os.makedirs(os.path.join(a.workdir, "bin"))
        copy = os.path.join(a.workdir, "bin", os.path.basename(a.pfflip))
        shutil.copy2(a.pfflip, copy)
        a.pfflip = copy
    cases = read_corpus(a.corpus)
    if a.filter:
        cases = [c for c in cases if re.search(a.filter, c["id"])]
    if a.ranks:
        keep = set(a.ranks.split(","))
        cases = [dict(c, ranks=",".join(n for n in c["ranks"].split(",") if n in keep)) for c in cases]
        cases = [c for c in cases if c["ranks"]]
    if not cases:
        sys.exit("run_corpus.py: no case selected")
    print(f"fuzz corpus: {len(cases)} cases from {a.corpus}, {a.jobs} jobs, time-out {a.timeout:g} s, "
          f"work in {a.workdir}", flush=True)
    t0 = time.monotonic()
    results = Runner(a).run(cases)
    wall = time.monotonic() - t0
    counts = {k: 0 for k in CLASSES}
    for r in results:
        counts[r["class"]] = counts.get(r["class"], 0) + 1
    if a.report:
        fields = ["id", "np", "class", "detail", "rc", "seconds", "category", "scene", "args", "expect", "error_lines",
                  "output_head"]
        with open(a.report, "w", newline="", encoding="utf-8") as f:
            w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
            w.writeheader()
            for r in results:
                w.writerow(r)
    if own_workdir and not a.keep:
        shutil.rmtree(a.workdir, ignore_errors=True)
    summary = ", ".join(f"{k} {counts[k]}" for k in CLASSES)
    bad = len(results) - counts["clean"]
    print(f"fuzz corpus: {len(results)} runs of {len(cases)} cases: {summary}; wall {wall:.1f} s"
          + (f"; {bad} runs not clean" if bad else "; all clean"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
