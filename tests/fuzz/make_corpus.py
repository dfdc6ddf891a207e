#!/usr/bin/python3
"""Writes tests/fuzz/corpus.tsv: bad inputs for pfflip, generated from the shipped scenes in config/.

    /usr/bin/python3 tests/fuzz/make_corpus.py [--config-dir config] [--out tests/fuzz/corpus.tsv]

The output is deterministic (no randomness, no time, no run of the binary): regenerate it only when the
scenes or the options change, and commit it with them. run_corpus.py runs it.

Every case must make pfflip exit with status 1 and print exactly one line "pfflip: error: ..." that
contains the case's expect string (the key, e.g. -gravity, or the file name), with no PETSc traceback
and no MPI_Abort banner, and without writing into -output_dir.

Columns (tab-separated, one header line; '#' lines are comments):
  id         unique, stable name: <scene>.<key>.<mutation>, or <kind>.<what>
  ranks      "1", or "1,2" for rank-local cases (files, output directory, restart)
  scene      a file of config/ (the base of the case), or "-" for none
  args       extra arguments, shell-quoted; run_corpus.py substitutes {out} (a fresh -output_dir that must not
             exist), {tmp} (the case's scratch directory), {file} (the file yaml_spec made) and {config}
  expect     the substring the single error line must contain; alternatives separated by " | "
  yaml_spec  empty, or the generator run_corpus.py uses to write {file} before the run (its YAML_GENERATORS and
             FILE_GENERATORS): a bad YAML scene (derived from the scene's text; it then replaces the scene as
             -options_file_yaml), or another file (a checkpoint from a fixture run, a text file, ...)
  category   the kind of bad input, for the counts

Unless yaml_spec names a YAML generator or scene is "-", run_corpus.py puts -options_file_yaml
config/<scene> in front of args. Every fluid case runs with -sim_max_steps 2 -sim_frames false and grid_demo
cases with -demo_steps 2, so an input that is wrongly accepted ends in about a second.
"""
import argparse
import os
import re
import shlex
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# The scenes the corpus is built from (config/<name>).
SCENES = {
    "dam": "dam_break_small.yaml",
    "dam2": "dam_break_small_2lev.yaml",
    "bub": "bubbles_small.yaml",
    "rt3d": "rt3d_small.yaml",
    "rtp": "rt_paper_small.yaml",
    "still": "still_water_small.yaml",
    "shear": "shear_sphere_small.yaml",
    "demo": "grid_demo_small.yaml",
}
FLOW_BASE = "-sim_max_steps 2 -sim_frames false -output_dir {out}"
DEMO_BASE = "-demo_steps 2 -demo_output_every 0 -output_dir {out}"

# Options of pfflip (pfflip -help and the PetscOptions* calls of src/): type and what values are valid.
#   real, int: scalar; real3, int3: 3 comma-separated values; bool; enum (with its values); str
#   'pos' > 0, 'nonneg' >= 0, 'unit' in [0, 1], 'open_unit' in (0, 1), 'cfl' in (0, 4]
OPTIONS = {
    # grid (every scene)
    "grid_cells": ("int3", "pos"),
    "grid_block_size": ("int", "pow2"),
    "grid_levels": ("int", "pos"),
    "grid_origin": ("real3", None),
    "grid_h": ("real", "pos"),
    "grid_periodic": ("str", None),
    "partition_type": ("enum", ("morton", "metis")),
    "grid_refine": ("enum", ("none", "plane", "sphere")),
    "grid_refine_point": ("real3", None),
    "grid_refine_normal": ("real3", None),
    "grid_refine_radius": ("real", "pos"),
    "grid_refine_band": ("real", "pos"),
    # simulation run (flow scenes)
    "sim_t_end": ("real", "pos"),
    "sim_output_interval": ("real", "nonneg"),
    "sim_max_steps": ("int", "nonneg"),
    "sim_frames": ("bool", None),
    "sim_frame_particles": ("bool", None),
    "sim_checkpoint_every": ("int", "nonneg"),
    "sim_restart": ("str", None),
    "sim_check_particles": ("bool", None),
    "sim_max_volume_drift": ("real", "nonneg"),
    "sim_max_gas_volume_drift": ("real", "nonneg"),
    # flow
    "rho_liquid": ("real", "pos"),
    "rho_gas": ("real", "pos"),
    "nu_liquid": ("real", "nonneg"),
    "nu_gas": ("real", "nonneg"),
    "gravity": ("real3", None),
    "flow_cfl": ("real", "cfl"),
    "flow_dt_max": ("real", "pos"),
    "flow_alpha_phi": ("real", "pos"),
    "flow_delta_phi": ("real", "unit"),
    "flow_flip": ("real", "unit"),
    "flow_pressure": ("bool", None),
    "flow_volume_correction": ("real", "unit"),
    "flow_volume_correction_max_displacement": ("real", "pos"),
    "flow_volume_correction_rtol": ("real", "open_unit"),
    "flow_volume_control": ("real", "nonneg"),
    "flow_delete_bubbles": ("bool", None),
    "flow_extrapolate_layers": ("int", "nonneg"),
    "particles_jitter": ("real", "unit"),
    "particles_seed": ("int", None),
    "particles_substep_cfl": ("real", "pos"),
    "particles_io_chunk": ("int", "pos"),
    # pressure
    "pressure_assembly": ("enum", ("ptap", "direct")),
    "pressure_operator": ("enum", ("aij", "shell")),
    "pressure_dirichlet_walls": ("str", None),
    "pressure_pc_type": ("enum", ("shell", "pffmg", "jacobi")),
    "pressure_ksp_type": ("enum", ("fcg", "cg")),
    "pressure_ksp_rtol": ("real", "open_unit"),
    "pressure_ksp_atol": ("real", "nonneg"),
    "pressure_ksp_divtol": ("real", "pos"),
    "pressure_ksp_max_it": ("int", "pos"),
    "pressure_pffmg_smoother": ("enum", ("rbgs", "jacobi")),
    "pressure_pffmg_adaptive_steps": ("int", "pos"),
    "pressure_pffmg_sweeps": ("int", "pos"),
    "pressure_pffmg_omega": ("real", "pos"),
    "pressure_pffmg_max_levels": ("int", "pos"),
    "pressure_pffmg_kcycle": ("int", "nonneg"),
    "pressure_pffmg_kcycle_rtol": ("real", "open_unit"),
    "pressure_pffmg_coarse_max": ("int", "pos"),
    "pressure_pffmg_theta_sigmas": ("real", None),
    "pressure_pffmg_coarse_pc_type": ("enum", ("redundant",)),
    # fluid scene
    "fluid_refine": ("enum", ("none", "surface")),
    "fluid_refine_band": ("real", "pos"),
    "liquid_0_type": ("enum", ("box", "sphere", "halfspace")),
    "liquid_0_lo": ("real3", None),
    "liquid_0_hi": ("real3", None),
    "liquid_0_velocity": ("real3", None),
    "gas_0_type": ("enum", ("box", "sphere", "halfspace")),
    "gas_0_center": ("real3", None),
    "gas_0_radius": ("real", "pos"),
    "solid_0_type": ("enum", ("box", "sphere")),
    "solid_0_lo": ("real3", None),
    "solid_0_hi": ("real3", None),
    # rt3d, rt_paper
    "rt_width": ("real", "pos"),
    "rt_resolution": ("int", "pos"),
    "rt_atwood": ("real", "open_unit"),
    "rt_gravity": ("real", "pos"),
    "rt_amplitude": ("real", "nonneg"),
    "rt_reynolds": ("real", "pos"),
    # still_water
    "still_level": ("real", "open_unit"),
    "still_max_velocity": ("real", "nonneg"),
    "still_ratio": ("real", "pos"),
    "still_resolution": ("int", "pos"),
    # shear_sphere
    "shear_resolution": ("int", "pos"),
    "shear_max_error": ("real", "nonneg"),
    "shear_u0": ("real", "pos"),
    "shear_periods": ("real", "pos"),
    # grid_demo
    "demo_steps": ("int", "nonneg"),
    "demo_output_every": ("int", "nonneg"),
    "demo_nu": ("real", "pos"),
    "demo_sigma": ("real", "pos"),
}
# Values for a vector option a scene does not set (pfflip's defaults or a valid value).
VECTOR_DEFAULTS = {"grid_origin": "0,0,0", "grid_refine_point": "0.5,0.5,0.5", "grid_refine_normal": "0,1,0",
                   "liquid_0_velocity": "0,0,0", "grid_cells": "32,32,32", "gravity": "0,-1,0"}


def parse_scene(path):
    """The options of a shipped scene, {key: value}: the subset of YAML the scenes use (top-level scalars,
    one level of block mappings, one-line flow mappings, comments)."""
    opts, section = {}, None
    with open(path, encoding="utf-8") as f:
        for raw in f:
            line = raw.split(" #")[0].rstrip() if not raw.lstrip().startswith("#") else ""
            if not line.strip():
                continue
            indent = len(line) - len(line.lstrip(" "))
            m = re.match(r"\s*([A-Za-z0-9_]+):\s*(.*)$", line)
            if not m:
                raise SystemExit(f"make_corpus.py: {path}: cannot read line {raw!r}")
            key, value = m.group(1), m.group(2).strip()
            if indent == 0:
                section = None
            elif section is None:
                raise SystemExit(f"make_corpus.py: {path}: indented line outside a section: {raw!r}")
            full = f"{section}_{key}" if indent and section else key
            if value == "":
                section = key
            elif value.startswith("{"):
                for item in re.findall(r'([A-Za-z0-9_]+):\s*("[^"]*"|[^,}]+)', value):
                    opts[f"{full}_{item[0]}"] = item[1].strip().strip('"')
            else:
                opts[full] = value.strip('"')
    return opts


def q(*words):
    return " ".join(shlex.quote(w) for w in words)


class Corpus:
    def __init__(self, config_dir):
        self.rows, self.ids = [], set()
        self.scene_opts = {short: parse_scene(os.path.join(config_dir, name)) for short, name in SCENES.items()}

    def add(self, cid, category, scene, args, expect, ranks="1", spec="", base=True):
        if cid in self.ids:
            raise SystemExit(f"make_corpus.py: duplicate id {cid}")
        self.ids.add(cid)
        name = SCENES[scene] if scene in SCENES else scene
        if base and scene in SCENES:
            args = (DEMO_BASE if scene == "demo" else FLOW_BASE) + (" " + args if args else "")
        for col in (cid, ranks, name, args, expect, spec, category):
            assert "\t" not in col and "\n" not in col, (cid, col)
        self.rows.append((cid, ranks, name, args, expect, spec, category))

    def value(self, scene, key):
        return self.scene_opts[scene].get(key, VECTOR_DEFAULTS.get(key, ""))

    def opt(self, scene, key, mut, value, category=None, expect=None, extra=""):
        """-key value on the command line of scene; the error must name -key."""
        assert key in OPTIONS, key
        args = (extra + " " if extra else "") + q("-" + key, value)
        self.add(f"{scene}.{key}.{mut}", category or classify(OPTIONS[key], value), scene, args, expect or "-" + key)

    def values(self, scene, key, values):
        """One case per value; the id names the mutation (MUTATION_NAMES) or the value."""
        for v in values:
            self.opt(scene, key, mutation_name(v), v)

    def vector(self, scene, key, muts):
        """Vector options, from the scene's value: too few / too many values, a non-numeric or non-finite
        component, empty items, spaces instead of commas, huge components."""
        base = self.value(scene, key).split(",")
        assert len(base) == 3, (scene, key, base)
        made = {"few": ",".join(base[:2]), "one": base[0], "many": ",".join(base + ["1"]),
                "five": ",".join(base + ["1", "2"]), "word": ",".join([base[0], "abc", base[2]]),
                "nan": ",".join(["nan"] + base[1:]), "inf": ",".join(base[:2] + ["inf"]),
                "holes": ",,", "trailing": ",".join(base) + ",", "spaces": " ".join(base),
                "huge": ",".join(["1e300"] * 3)}
        for m in muts:
            cat = {"nan": "non-finite", "inf": "non-finite", "huge": "huge"}.get(m, "vector")
            self.opt(scene, key, m, made[m], cat)


# id suffixes of mutated values
MUTATION_NAMES = {"nan": "nan", "inf": "inf", "-inf": "neginf", "1e300": "huge", "-1e300": "neghuge", "abc": "abc",
                  "": "empty", "true": "true", "~": "tilde", "1.5": "frac", "maybe": "maybe", "2": "two",
                  "0x10": "hex", "1,2": "list", "12abc": "trailing", "0": "zero", "-1": "neg", "nosuch": "nosuch",
                  "99999999999999999999": "overflow"}


def mutation_name(v):
    if v in MUTATION_NAMES:
        return MUTATION_NAMES[v]
    return ("neg" if v.startswith("-") else "v") + "".join(ch if ch.isalnum() else "_" for ch in v.lstrip("-"))


def classify(opt, value):
    """The category of a bad value of an option of type opt = (type, constraint)."""
    typ, _ = opt
    if typ in ("bool", "enum", "str"):
        return {"bool": "wrong type", "enum": "enum", "str": "out of range"}[typ]
    if value.lower() in ("nan", "inf", "-inf"):
        return "non-finite"
    nums = []
    for item in value.split(","):
        try:
            nums.append(float(item))
        except ValueError:
            return "wrong type"
    if any(abs(x) >= (1e3 if typ.startswith("int") else 1e5) for x in nums):
        return "huge"
    if typ.startswith("int") and any(x != int(x) for x in nums):
        return "wrong type"
    return "out of range"


def build(config_dir):
    c = Corpus(config_dir)
    V = c.values

    # ---- dam break (fluid scene): flow, sim, particles, grid, geometry, pressure ----------------
    c.vector("dam", "gravity", ("few", "many", "word", "nan", "holes", "spaces", "huge"))
    c.vector("dam", "liquid_0_lo", ("few", "many", "word"))
    c.vector("dam", "liquid_0_hi", ("one", "inf"))
    c.vector("dam", "liquid_0_velocity", ("five", "nan"))
    c.vector("dam", "solid_0_lo", ("word",))
    c.vector("dam", "solid_0_hi", ("trailing",))
    c.vector("dam", "grid_cells", ("few", "many"))
    c.vector("dam", "grid_origin", ("few", "nan"))
    V("dam", "rho_liquid", ("nan", "inf", "-inf", "1e300", "-1e300", "0", "-1", "abc", "", "true", "~", "12abc"))
    V("dam", "rho_gas", ("nan", "0", "-1", "1,2"))
    V("dam", "nu_liquid", ("nan", "-1"))
    V("dam", "nu_gas", ("-1e-6",))
    V("dam", "flow_cfl", ("nan", "inf", "0", "-1", "1e300"))
    V("dam", "flow_dt_max", ("nan", "0", "-1"))
    V("dam", "flow_alpha_phi", ("nan", "-1"))
    V("dam", "flow_delta_phi", ("-0.5",))
    V("dam", "flow_flip", ("nan", "1.5"))
    V("dam", "flow_volume_correction", ("nan", "-0.5"))
    V("dam", "flow_volume_correction_max_displacement", ("0",))
    V("dam", "flow_volume_correction_rtol", ("nan", "-1"))
    V("dam", "flow_volume_control", ("nan", "-1", "3"))
    V("dam", "flow_extrapolate_layers", ("1.5", "abc", "99999999999999999999"))
    V("dam", "flow_pressure", ("maybe",))
    V("dam", "flow_delete_bubbles", ("nan",))
    V("dam", "particles_jitter", ("nan", "-1"))
    V("dam", "particles_seed", ("1.5",))
    V("dam", "particles_substep_cfl", ("nan", "0"))
    V("dam", "particles_io_chunk", ("0", "1.5"))
    V("dam", "sim_t_end", ("nan", "inf", "0", "-1"))
    V("dam", "sim_output_interval", ("nan", "-1"))
    V("dam", "sim_max_steps", ("1.5", "-1", "1e300"))
    V("dam", "sim_frames", ("maybe",))
    V("dam", "sim_frame_particles", ("2",))
    V("dam", "sim_checkpoint_every", ("-1",))
    V("dam", "sim_max_volume_drift", ("inf",))
    V("dam", "sim_max_gas_volume_drift", ("abc",))
    # grid
    V("dam", "grid_cells", ("0,0,0", "-32,16,8", "33,16,8", "99999999999,16,8", "4096,4096,4096"))
    V("dam", "grid_block_size", ("0", "6", "1.5"))
    V("dam", "grid_levels", ("0", "100"))
    V("dam", "grid_h", ("nan", "0", "-0.0625", "1e300"))
    V("dam", "grid_periodic", ("w", "x,x"))
    V("dam", "partition_type", ("nosuch", ""))
    V("dam", "grid_refine", ("nosuch",))
    V("dam", "grid_refine_radius", ("-1",))
    # geometry
    V("dam", "liquid_0_type", ("nosuch",))
    V("dam", "solid_0_type", ("halfspace",))
    c.opt("dam", "liquid_0_hi", "below_lo", "-0.6,-0.6,-0.5", "geometry")
    c.opt("dam", "liquid_0_lo", "outside", "10,10,10", "geometry", expect="-liquid_0", extra="-liquid_0_hi 11,11,11")
    c.opt("dam", "solid_0_hi", "outside", "1e300,0.15,0.375", "geometry")
    c.opt("dam", "liquid_0_type", "sphere_no_center", "sphere", "geometry", expect="-liquid_0_")
    c.opt("dam", "liquid_0_type", "halfspace_nonormal", "halfspace", "geometry", expect="-liquid_0_")
    c.add("dam.liquid_2_type.gap", "geometry", "dam", q("-liquid_2_type", "box"), "-liquid_2_type")
    c.add("dam.liquid_0_radius.unused", "geometry", "dam", q("-liquid_0_radius", "1"), "-liquid_0_radius")
    # pressure solver (PETSc's own options among them)
    for key, values in (("pressure_ksp_rtol", ("nan", "-1", "inf")), ("pressure_ksp_atol", ("-1",)),
                        ("pressure_ksp_max_it", ("-1",)), ("pressure_pc_type", ("nosuch",)),
                        ("pressure_ksp_type", ("nosuch",)), ("pressure_assembly", ("nosuch",)),
                        ("pressure_operator", ("",)), ("pressure_pffmg_sweeps", ("-1",)),
                        ("pressure_pffmg_omega", ("nan",)), ("pressure_pffmg_kcycle_rtol", ("1", "-0.5")),
                        ("pressure_dirichlet_walls", ("xmin,nosuch",))):
        for v in values:
            c.opt("dam", key, mutation_name(v), v, "solver")
    # unknown and misspelt keys
    for cid, key in (("misspelt_gravity", "-gravitty"), ("misspelt_rho", "-rho_liqiud"), ("misspelt_grid", "-grid_cell"),
                     ("unknown", "-nosuch_key"), ("wrong_scene_key", "-rt_atwood"), ("gas_velocity", "-gas_0_velocity")):
        c.add(f"dam.unknown.{cid}", "unknown key", "dam", q(key, "1"), key)
    c.add("dam.unknown.flag", "unknown key", "dam", q("-nosuch_flag"), "-nosuch_flag")
    c.add("dam.scene.nosuch", "enum", "dam", q("-scene", "nosuch"), "-scene")
    c.add("dam.scene.empty", "enum", "dam", q("-scene", ""), "-scene")
    # fluid_refine (the 2-level scene)
    V("dam2", "fluid_refine", ("nosuch",))
    V("dam2", "fluid_refine_band", ("nan", "-1"))

    # ---- bubbles (gas regions) --------------------------------------------------------------
    c.vector("bub", "gas_0_center", ("few", "word"))
    V("bub", "gas_0_radius", ("nan", "0", "-1e-3"))
    V("bub", "gas_0_type", ("nosuch",))

    # ---- rt3d and rt_paper -----------------------------------------------------------------
    V("rt3d", "rt_atwood", ("nan", "0", "2"))
    V("rt3d", "rt_width", ("0",))
    V("rt3d", "rt_resolution", ("1.5", "0", "17", "100000"))
    V("rt3d", "rt_gravity", ("nan", "-1"))
    V("rt3d", "rt_amplitude", ("-0.05",))
    V("rt3d", "rt_reynolds", ("0",))
    c.vector("rt3d", "gravity", ("few",))
    V("rtp", "rt_atwood", ("1",))
    V("rtp", "rt_resolution", ("0",))

    # ---- still water -----------------------------------------------------------------------
    V("still", "still_level", ("nan", "0", "2"))
    V("still", "still_ratio", ("inf", "-1000"))
    V("still", "still_resolution", ("0", "100000"))

    # ---- shear sphere ----------------------------------------------------------------------
    V("shear", "shear_resolution", ("0", "1000000", "abc"))
    V("shear", "shear_u0", ("nan",))
    V("shear", "shear_periods", ("-2",))
    V("shear", "shear_max_error", ("-1",))

    # ---- grid demo -------------------------------------------------------------------------
    V("demo", "demo_steps", ("-1", "1.5"))
    V("demo", "demo_nu", ("nan", "0"))
    c.vector("demo", "grid_refine_point", ("few", "word"))
    c.opt("demo", "grid_refine_normal", "zero", "0,0,0", "out of range", extra="-grid_refine plane")
    V("demo", "grid_refine_radius", ("inf",))
    V("demo", "grid_refine_band", ("0",))
    V("demo", "grid_levels", ("5",))
    V("demo", "grid_refine", ("nosuch",))
    c.add("demo.unknown.sim_key", "unknown key", "demo", q("-sim_t_end", "1"), "-sim_t_end")
    c.add("demo.unknown.misspelt", "unknown key", "demo", q("-demo_step", "2"), "-demo_step")
    c.add("demo.scene.nosuch", "enum", "demo", q("-scene", "nosuch"), "-scene")

    # ---- stray positional arguments ----------------------------------------------------------
    c.add("args.stray_end", "positional", "dam", "straytoken", "straytoken")
    c.add("args.stray_after_value", "positional", "dam", q("-rho_gas", "1", "straytoken"), "straytoken")
    c.add("args.stray_before_options", "positional", "-",
          "straytoken -options_file_yaml {config}/dam_break_small.yaml " + FLOW_BASE, "straytoken")
    c.add("args.scene_without_key", "positional", "-", "{config}/dam_break_small.yaml " + FLOW_BASE,
          "dam_break_small.yaml")
    c.add("args.value_twice", "positional", "dam", q("-sim_frames", "false", "false"), "false")

    # ---- option files (rank-local: each rank opens them) ------------------------------------
    R = "1,2"
    c.add("file.yaml_missing", "file", "-", "-options_file_yaml {tmp}/missing.yaml " + FLOW_BASE, "missing.yaml", R)
    c.add("file.yaml_missing_second", "file", "dam", "-options_file_yaml {tmp}/second_missing.yaml",
          "second_missing.yaml", R)
    c.add("file.yaml_directory", "file", "-", "-options_file_yaml {file} " + FLOW_BASE, "-options_file_yaml | a_directory",
          R, "directory")
    c.add("file.yaml_no_value", "file", "dam", "-options_file_yaml", "-options_file_yaml", R)
    c.add("file.yaml_devnull", "file", "-", "-options_file_yaml /dev/null " + FLOW_BASE, "/dev/null")
    c.add("file.options_file_missing", "file", "dam", "-options_file {tmp}/missing.opts", "missing.opts", R)
    c.add("file.options_file_directory", "file", "dam", "-options_file {file}", "-options_file | a_directory", "1",
          "directory")
    c.add("file.options_file_garbage", "file", "dam", "-options_file {file}", "garbage.bin | -options_file",
          spec="binary_garbage_file")

    # ---- output directory (rank-local: each rank checks it) ---------------------------------
    c.add("outdir.regular_file", "output dir", "dam", "-output_dir {file}", "-output_dir", R, "text_file")
    c.add("outdir.under_regular_file", "output dir", "dam", "-output_dir {file}/sub", "-output_dir", R, "text_file")
    c.add("outdir.empty", "output dir", "dam", "-output_dir ''", "-output_dir", R)
    c.add("outdir.proc", "output dir", "dam", "-output_dir /proc/forbidden", "-output_dir")
    c.add("outdir.devnull", "output dir", "dam", "-output_dir /dev/null", "-output_dir", R)
    c.add("outdir.too_long", "output dir", "dam", "-output_dir {tmp}/" + "d" * 5000, "-output_dir")
    c.add("outdir.demo_regular_file", "output dir", "demo", "-output_dir {file}", "-output_dir", R, "text_file")

    # ---- restart (rank-local: each rank reads the checkpoint) -------------------------------
    c.add("restart.missing", "restart", "dam", "-sim_restart {tmp}/missing_checkpoint.h5", "missing_checkpoint.h5", R)
    # the error names -sim_restart or the file (run_corpus.py's FILE_GENERATORS name the files)
    c.add("restart.directory", "restart", "dam", "-sim_restart {file}", "-sim_restart | a_directory", R, "directory")
    c.add("restart.text_file", "restart", "dam", "-sim_restart {file}", "-sim_restart | plain.txt", R, "text_file")
    c.add("restart.empty_file", "restart", "dam", "-sim_restart {file}", "-sim_restart | empty.h5", "1", "empty_file")
    c.add("restart.fake_hdf5", "restart", "dam", "-sim_restart {file}", "-sim_restart | fake.h5", R, "fake_hdf5")
    c.add("restart.truncated", "restart", "dam", "-sim_restart {file}", "-sim_restart | truncated_checkpoint.h5", R,
          "checkpoint_truncated")
    c.add("restart.frame_not_checkpoint", "restart", "dam", "-sim_restart {file}", "-sim_restart | frame_0000.h5", R,
          "frame")
    c.add("restart.other_scene", "restart", "rt3d", "-sim_restart {file}", "-sim_restart | checkpoint.h5", R,
          "checkpoint")
    c.add("restart.other_grid", "restart", "dam", "-sim_restart {file} -grid_cells 64,32,16 -grid_h 0.03125",
          "-sim_restart | checkpoint.h5", "1", "checkpoint")

    # ---- bad YAML scene files (written by run_corpus.py from the scene's text) ---------------
    # expect: the generated file's name (run_corpus.py names it <generator>.yaml), or the key it spoils
    yaml_cases = [
        ("unclosed_quote", "dam", R, ""), ("unclosed_quote", "rt3d", "1", ""), ("unclosed_brace", "dam", R, ""),
        ("tab_indent", "dam", "1", ""), ("truncated", "dam", R, ""), ("truncated", "shear", "1", ""),
        ("top_level_list", "dam", "1", ""), ("top_level_scalar", "dam", "1", ""),
        ("deep_nesting", "dam", "1", " | -n00_n01"), ("binary_garbage", "dam", R, ""), ("nul_byte", "dam", R, ""),
        ("empty", "dam", R, ""), ("bad_indent", "still", "1", ""), ("invalid_utf8", "dam", "1", ""),
        ("undefined_alias", "dam", "1", ""), ("yaml_directive", "dam", "1", ""),
        ("long_key", "dam", "1", " | -kkkkkkkk"), ("long_value", "dam", "1", " | -scene"),
        ("duplicate_key", "dam", "1", " | -rho_gas"), ("mapping_as_value", "dam", "1", " | -rho_gas_"),
        ("list_as_value", "dam", "1", " | -rho_gas"), ("null_value", "dam", "1", " | -rho_gas"),
    ]
    for gen, scene, ranks, alt in yaml_cases:
        c.add(f"yaml.{gen}.{scene}", "yaml file", scene, "", f"{gen}.yaml{alt}", ranks, gen)
    for scene, sec, bad in (("dam", "grid", "gird"), ("rt3d", "rt", "tr")):
        c.add(f"yaml.misspelt_section.{scene}", "yaml file", scene, "", f"-{bad}_ | misspelt_section.yaml", "1",
              f"misspelt_section:{sec}={bad}")
    # bad values inside the scene file: the error names the key as on the command line
    for scene, key, value in (("dam", "gravity", "0,-9.81"), ("dam", "rho_gas", "-1"), ("dam", "grid.block_size", "abc"),
                              ("dam", "liquid_0.lo", "0,0"), ("dam", "sim.t_end", "inf"), ("rt3d", "rt.atwood", "nan"),
                              ("still", "still.level", "2"), ("bub", "gas_0.radius", "0")):
        mut = mutation_name(value)
        c.add(f"yaml.value.{scene}.{key.replace('.', '_')}.{mut}", "yaml value", scene, "",
              "-" + key.replace(".", "_"), "1", f"set:{key}={value}")
    return c


HEADER = ("id", "ranks", "scene", "args", "expect", "yaml_spec", "category")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--config-dir", default=os.path.join(ROOT, "config"))
    ap.add_argument("--out", default=os.path.join(HERE, "corpus.tsv"))
    a = ap.parse_args()
    c = build(a.config_dir)
    lines = ["# pfflip fuzz corpus: bad inputs generated from config/*.yaml by tests/fuzz/make_corpus.py (do not edit;",
             "# regenerate). Run: tests/fuzz/run_corpus.py <pfflip> '<mpiexec ...>' tests/fuzz/corpus.tsv",
             "\t".join(HEADER)]
    lines += ["\t".join(r) for r in c.rows]
    with open(a.out, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
    cats = {}
    runs = 0
    for r in c.rows:
        cats[r[6]] = cats.get(r[6], 0) + 1
        runs += len(r[1].split(","))
    print(f"{a.out}: {len(c.rows)} cases, {runs} runs; " + ", ".join(f"{k} {v}" for k, v in cats.items()))


if __name__ == "__main__":
    sys.exit(main())
