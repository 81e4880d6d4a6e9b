"""Start-up of ``doodle compile`` (bench/startup.py measures it): the numpy stand-ins for
scipy.signal give scipy's results; the command line and a compile import none of the heavy
libraries they no longer need; the disk cache of analysed clips and automata
(doodle.app.libcache) gives the same output cold and warm, follows the library's files and
shrugs off a broken entry."""

import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks as scipy_find_peaks
from scipy.signal import savgol_coeffs as scipy_savgol_coeffs

from doodle.core import cache
from doodle.core.peaks import find_peaks
from doodle.input.smoothing import savgol_coeffs, savgol_kernel

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"
BUILTIN_CLIPS = ROOT / "library" / "builtin" / "clips"


# --- numpy stand-ins for scipy.signal ----------------------------------------------------------

@pytest.mark.parametrize("window", range(2, 64))
def test_savgol_coeffs_equal_scipys(window):
    for order in range(0, min(window, 7)):
        ours, theirs = savgol_coeffs(window, order), scipy_savgol_coeffs(window, order)
        assert ours.shape == theirs.shape
        assert np.max(np.abs(ours - theirs)) <= 1e-12


def test_savgol_kernels_of_the_segmenter_equal_scipys_bit_for_bit():
    for rate in (30.0, 60.0, 72.0, 90.0, 120.0, 144.0, 240.0):
        for window in (0.05, 0.1, 0.2):
            kernel = savgol_kernel(window, rate)
            assert np.array_equal(kernel, scipy_savgol_coeffs(len(kernel), 3))


def test_savgol_coeffs_refuse_an_order_as_long_as_the_window():
    with pytest.raises(ValueError):
        savgol_coeffs(3, 3)


def _same_peaks(x, **options):
    ours, props = find_peaks(x, **options)
    theirs, their_props = scipy_find_peaks(x, **options)
    assert np.array_equal(ours, theirs) and ours.dtype == theirs.dtype, options
    assert props.keys() == their_props.keys(), options
    for key in props:
        assert np.array_equal(props[key], their_props[key]) and props[key].dtype == their_props[key].dtype, (key, options)
    return ours


def _options(x, rng):
    """The option sets the program uses (retarget.analysis, laban.features) and a few more."""
    span = float(np.ptp(x)) if len(x) else 1.0
    low = float(np.min(x)) if len(x) else 0.0
    return [{}, {"plateau_size": 1}, {"prominence": 0.0, "plateau_size": 1},
            {"height": -(low + 0.3 * span), "prominence": 0.2 * span, "plateau_size": 1},
            {"height": low + 0.5 * span, "prominence": span / 3, "distance": int(rng.integers(1, 12))},
            {"height": 0.05 * span, "prominence": 0.3 * 0.05 * span}, {"distance": 2.5},
            {"prominence": (0.1 * span, 0.8 * span)}, {"height": (None, low + 0.7 * span)},
            {"plateau_size": (2, 4)}, {"height": rng.normal(size=len(x))}]


def test_find_peaks_equals_scipys_on_random_signals_with_plateaus():
    rng = np.random.default_rng(1)
    for _ in range(1500):
        n = int(rng.integers(0, 80))
        x = np.round(rng.normal(size=n), int(rng.integers(0, 3)))  # coarse rounding: flat runs and ties
        for options in _options(x, rng):
            _same_peaks(x, **options)


def test_find_peaks_equals_scipys_on_real_speeds():
    from doodle.input.loader import load
    from laban.features import _norm, effort_signal
    from retarget.analysis import body_speed
    from retarget.bvh import read_bvh
    from retarget.skeleton import forward_kinematics

    rng = np.random.default_rng(2)
    signals = []
    for path in sorted(BUILTIN_CLIPS.glob("*.bvh")):  # body speed: stages and repetitions of clips
        motion = read_bvh(path)
        speed, _ = body_speed(motion, forward_kinematics(motion)[0])
        signals += [speed, -speed]
    track = load(DEMO).tracks[0]  # the hand's speed over stretches of the demo: strokes (laban.features)
    for start in range(0, len(track.t) - 60, 45):
        _, v, _, _, _ = effort_signal(track.t[start:start + 90], track.p[start:start + 90])
        speed = _norm(v)
        signals.append(np.concatenate([[0.0], speed, [0.0]]))
    found = 0
    for x in signals:
        for options in _options(x, rng):
            found += len(_same_peaks(x, **options))
    assert found > 1000


def test_find_peaks_checks_its_input_like_scipy():
    with pytest.raises(ValueError):
        find_peaks(np.zeros((3, 3)))
    with pytest.raises(ValueError):
        find_peaks(np.arange(5.0), distance=0.5)
    with pytest.raises(ValueError):
        find_peaks(np.arange(5.0), height=np.zeros(4))


def test_the_front_of_quaternions_equals_scipys_to_the_bit():
    from scipy.spatial.transform import Rotation

    from doodle.core.quat import front
    from doodle.input.loader import load

    rng = np.random.default_rng(3)
    q = np.concatenate([rng.normal(size=(20000, 4)), rng.normal(size=(2000, 4)) * 1e-150,
                        load(DEMO).tracks[0].q, [[0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0]]])
    assert np.array_equal(front(q), Rotation.from_quat(q).apply([0.0, 0.0, 1.0]))
    assert np.array_equal(front(q[7]), Rotation.from_quat(q[7]).apply([0.0, 0.0, 1.0]))
    with pytest.raises(ValueError):
        front(np.zeros(4))


# --- what is imported ---------------------------------------------------------------------------

HEAVY = ("pandas", "sklearn", "scipy.signal", "scipy.stats", "scipy.ndimage", "scipy.interpolate", "scipy.sparse",
         "scipy.spatial", "scipy.optimize", "scipy.linalg", "matplotlib", "trimesh", "hmmlearn")


def _imported(code: str, tmp_path) -> set:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               DOODLE_CACHE=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys; print(' '.join(sorted(sys.modules)))"],
                         cwd=ROOT, env=env, capture_output=True, text=True, check=True).stdout
    return set(out.splitlines()[-1].split())


def test_the_command_line_parser_imports_no_numerical_library(tmp_path):
    mods = _imported("from doodle.app.cli.main import build_parser; build_parser()", tmp_path)
    assert not {m for m in mods if m.split(".")[0] in ("numpy", "scipy", "pandas", "sklearn", "lark")}



def test_a_command_builds_and_imports_only_its_own_parser(tmp_path):
    """``doodle --help`` imports no command's module; ``doodle compile`` only its own."""
    code = "from doodle.app.cli.main import build_parser, named_command; build_parser(named_command({!r}))"
    cli = {"doodle.app.cli", "doodle.app.cli.main", "doodle.app.cli.options"}
    mods = _imported(code.format(["--help"]), tmp_path)
    assert {m for m in mods if m.startswith("doodle.app.cli")} == cli
    mods = _imported(code.format(["compile", "x", "-o", "y"]), tmp_path)
    assert {m for m in mods if m.startswith("doodle.app.cli")} == cli | {"doodle.app.cli.compile"}

def test_a_compile_imports_no_library_it_does_not_use(tmp_path):
    code = (f"from doodle.app.cli.main import main; main(['compile', {str(DEMO)!r}, '-o', {str(tmp_path / 'out')!r}])\n"
            f"main(['compile', {str(DEMO)!r}, '-o', {str(tmp_path / 'out')!r}])")
    mods = _imported(code, tmp_path)
    assert not {m for m in mods if m in HEAVY or m.split(".")[0] in ("pandas", "sklearn", "matplotlib", "hmmlearn")}
    warm = _imported(f"from doodle.app.cli.main import main; main(['compile', {str(DEMO)!r}, '-o', "
                     f"{str(tmp_path / 'out')!r}])", tmp_path)  # the cache filled above
    assert "lark" not in warm  # the automata come from the cache: no expression parsed


def test_recognising_from_the_cache_imports_no_scipy(tmp_path):
    code = f"from doodle.app.cli.main import main; main(['recognize', {str(DEMO)!r}])"
    _imported(code, tmp_path)  # the automata cached
    mods = _imported(code, tmp_path)
    assert not {m for m in mods if m.split(".")[0] in ("scipy", "lark", "pandas", "sklearn")}


def _scipy_spatial_imports(module: str) -> list[str]:
    """The scipy.spatial modules a module of ours imports anywhere in its source."""
    import ast

    path = ROOT.joinpath(*module.split("."))
    path = path.with_suffix(".py") if path.with_suffix(".py").is_file() else path / "__init__.py"
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
            [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
        found += [n for n in names if n == "scipy.spatial" or n.startswith("scipy.spatial.")]
    return found


def test_compiling_recognising_and_replaying_use_no_scipy_spatial(tmp_path):
    """Rotations on these paths are doodle.core.quat's: none of the modules they import
    imports scipy.spatial (a 0.4 s import); retarget.terrain, whose mesh terrain's KD-tree
    does, is imported only for ``--terrain``."""
    code = (f"from doodle.app.cli.main import main; main(['compile', {str(DEMO)!r}, '-o', {str(tmp_path / 'out')!r}])\n"
            f"main(['recognize', {str(DEMO)!r}]); main(['replay', {str(DEMO)!r}, '--speed', '0'])")
    mods = _imported(code, tmp_path)
    ours = sorted(m for m in mods if m.split(".")[0] in ("doodle", "grammar", "laban", "retarget", "library"))
    assert {"retarget.bvh", "retarget.sequence", "doodle.app.placement", "doodle.app.replay"} <= set(ours)
    found = {m: _scipy_spatial_imports(m) for m in ours}
    assert {m: f for m, f in found.items() if f} == {} and "retarget.terrain" not in ours


# --- the cache ----------------------------------------------------------------------------------

@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("DOODLE_CACHE", str(folder))
    monkeypatch.delenv("DOODLE_NO_CACHE", raising=False)
    return folder


def _entries(folder: Path, kind: str) -> list[Path]:
    return sorted(folder.glob(f"doodle-{kind}-*.npz"))


def test_the_cache_folder_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.delenv("DOODLE_NO_CACHE", raising=False)
    monkeypatch.setenv("DOODLE_CACHE", str(tmp_path / "mine"))
    assert cache.folder() == tmp_path / "mine"
    monkeypatch.delenv("DOODLE_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache.folder() == tmp_path / "xdg" / "doodle"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache.folder() == tmp_path / "home" / ".cache" / "doodle"
    monkeypatch.setenv("DOODLE_NO_CACHE", "1")
    assert cache.folder() is None


def _compile(out: Path, *extra, env=None) -> tuple[bytes, str]:
    run_env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    run_env.update(env or {})
    subprocess.run([sys.executable, "-m", "doodle.app.cli.main", "compile", str(DEMO), "-o", str(out), *extra],
                   cwd=ROOT, env=run_env, check=True, capture_output=True)
    return (out / "c0.bvh").read_bytes(), (out / "report.json").read_text()


def test_a_compile_is_the_same_with_the_cache_cold_warm_or_off(cache_dir, tmp_path):
    out = tmp_path / "out"  # one output folder: the report names it
    cold = _compile(out)
    assert [len(_entries(cache_dir, k)) for k in ("clips", "dfas", "automaton")] == [1, 1, 1]
    warm = _compile(out)
    off = _compile(out, "--no-cache", env={"DOODLE_CACHE": str(tmp_path / "unused")})
    off_env = _compile(out, env={"DOODLE_NO_CACHE": "1", "DOODLE_CACHE": str(tmp_path / "unused")})
    assert cold == warm == off == off_env
    assert not (tmp_path / "unused").exists()
    assert json.loads(cold[1])["tracks"]["c0"]["frames"] == 259


def _user_library(folder: Path) -> Path:
    """A small user library: a new action whose clip has no stages given (so they are
    extracted: retarget.analysis, find_peaks) and an overridden Walk."""
    (folder / "clips").mkdir(parents=True)
    shutil.copy(BUILTIN_CLIPS / "greet.bvh", folder / "clips" / "wave.bvh")
    shutil.copy(BUILTIN_CLIPS / "walk.bvh", folder / "clips" / "stroll.bvh")
    (folder / "library.toml").write_text(
        '[library]\nname = "mine"\n\n'
        '[[actions]]\nname = "Wave"\nexpression = "(T_X | T_N_X)+ T_Y"\ncyclic = false\nin_place = true\n'
        'jumping = false\nclips = ["clips/wave.bvh"]\n\n'
        '[[actions]]\nname = "Walk"\ncyclic = true\nin_place = false\njumping = false\nclips = ["clips/stroll.bvh"]\n',
        encoding="utf-8")
    return folder


def _same_actions(a, b) -> None:
    assert a.library == b.library and a.user == b.user and a.directions == b.directions
    assert a.clips.keys() == b.clips.keys()
    for name in a.clips:
        for x, y in zip(a.clips[name], b.clips[name], strict=True):
            assert (x.action, x.path, x.roles, x.stages, x.cycle_length, x.travel, x.retargeted) == (
                y.action, y.path, y.roles, y.stages, y.cycle_length, y.travel, y.retargeted)
            assert np.array_equal(x.contacts, y.contacts)
            mx, my = x.motion, y.motion
            assert mx.frame_time == my.frame_time and mx.skeleton.names == my.skeleton.names
            assert mx.skeleton.channels == my.skeleton.channels
            assert np.array_equal(mx.skeleton.parents, my.skeleton.parents)
            assert np.array_equal(mx.skeleton.offsets, my.skeleton.offsets)
            assert mx.skeleton.end_sites.keys() == my.skeleton.end_sites.keys()
            assert all(np.array_equal(mx.skeleton.end_sites[j], my.skeleton.end_sites[j]) for j in mx.skeleton.end_sites)
            assert np.array_equal(mx.translations, my.translations) and np.array_equal(mx.rotations, my.rotations)
    for da, db in zip(a.compiled.dfas, b.compiled.dfas, strict=True):
        assert np.array_equal(da.table, db.table) and np.array_equal(da.accept, db.accept)


def test_cached_clips_and_automata_are_what_the_analysis_gives(cache_dir, tmp_path):
    from doodle.app.pipeline import load_for_compile

    lib = _user_library(tmp_path / "mine")
    fresh = load_for_compile(lib, cache=False)
    assert not cache_dir.exists()
    cold = load_for_compile(lib)
    warm = load_for_compile(lib)
    _same_actions(fresh, cold)
    _same_actions(fresh, warm)
    tables = [a.automaton(2.0).tables() for a in (fresh.compiled, cold.compiled, load_for_compile(lib).compiled)]
    for other in tables[1:]:
        assert other.keys() == tables[0].keys()
        assert all(np.array_equal(other[k], tables[0][k]) for k in other)
    assert len(_entries(cache_dir, "automaton")) == 1


def test_the_cache_follows_the_library_files(cache_dir, tmp_path):
    from doodle.app.pipeline import load_for_compile
    from retarget.bvh import read_bvh, write_bvh

    lib = _user_library(tmp_path / "mine")
    before = load_for_compile(lib)
    assert len(_entries(cache_dir, "clips")) == 1
    clip = lib / "clips" / "wave.bvh"  # the clip changes: the left arm turned 90° on one frame
    motion = read_bvh(clip)
    rotations = motion.rotations.copy()
    rotations[5, motion.skeleton.index("LeftArm")] = (0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5))
    write_bvh(clip, type(motion)(motion.skeleton, motion.translations, rotations, motion.frame_time))
    after = load_for_compile(lib)
    assert len(_entries(cache_dir, "clips")) == 2  # a new key; the old entry is left, never read again
    assert not np.array_equal(after.clips["Wave"][0].motion.rotations, before.clips["Wave"][0].motion.rotations)
    _same_actions(load_for_compile(lib, cache=False), after)
    manifest = lib / "library.toml"  # the manifest changes: another expression, stages given
    manifest.write_text(manifest.read_text().replace('"(T_X | T_N_X)+ T_Y"', '"(T_X | T_N_X)+"')
                        .replace('clips = ["clips/wave.bvh"]', 'clips = ["clips/wave.bvh"]\nstages = [2, 4, 6, 8]'))
    changed = load_for_compile(lib)
    assert len(_entries(cache_dir, "clips")) == 3 and len(_entries(cache_dir, "dfas")) == 2
    assert changed.clips["Wave"][0].stages.execution == 6
    _same_actions(load_for_compile(lib, cache=False), changed)


@pytest.mark.parametrize("damage", ["empty", "truncated", "garbage", "other entry", "wrong arrays", "pickle"])
def test_a_broken_cache_entry_is_ignored_and_rebuilt(cache_dir, tmp_path, damage):
    from doodle.app.pipeline import load_for_compile

    lib = _user_library(tmp_path / "mine")
    fresh = load_for_compile(lib, cache=False)
    load_for_compile(lib).compiled.automaton(2.0)
    entries = [p for k in ("clips", "dfas", "automaton") for p in _entries(cache_dir, k)]
    assert len(entries) == 3
    for path in entries:
        data = path.read_bytes()
        if damage == "empty":
            path.write_bytes(b"")
        elif damage == "truncated":
            path.write_bytes(data[: len(data) // 2])
        elif damage == "garbage":
            path.write_bytes(np.random.default_rng(0).bytes(len(data)))
        elif damage == "other entry":  # a valid entry under another key's name
            np.savez(path, meta=np.array(json.dumps({"format": 1, "kind": "clips", "key": "0" * 64})))
        elif damage == "wrong arrays":  # the right header, arrays that do not fit
            import zipfile

            with zipfile.ZipFile(path) as z:
                meta = np.load(z.open("meta.npy"))
            np.savez(path, meta=meta, c0_translations=np.zeros((2, 2)), dfa0_table=np.zeros(3),
                     step_lengths=np.ones(3, dtype=np.int64))
        else:  # an array declaring objects (a pickle would follow): refused unread
            import io
            import zipfile

            header = io.BytesIO()
            np.lib.format.write_array_header_1_0(header, {"descr": "|O", "fortran_order": False, "shape": (1,)})
            with zipfile.ZipFile(path, "w") as z:
                z.writestr("meta.npy", header.getvalue() + b"\x80\x04not a pickle to load")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not even a warning
        again = load_for_compile(lib)
        again.compiled.automaton(2.0)
    _same_actions(fresh, again)
    assert np.array_equal(again.compiled.automaton(2.0).tables()["step_src"],
                          fresh.compiled.automaton(2.0).tables()["step_src"])
    reread = load_for_compile(lib)  # rebuilt: readable again
    _same_actions(fresh, reread)
    assert all(cache.read(p.name.split("-")[1], p.stem.split("-")[2]) is not None
               for k in ("clips", "dfas", "automaton") for p in _entries(cache_dir, k))


def test_a_cache_folder_that_cannot_be_written_is_skipped(tmp_path, monkeypatch):
    from doodle.app.pipeline import load_for_compile

    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("DOODLE_CACHE", str(blocker / "cache"))
    monkeypatch.delenv("DOODLE_NO_CACHE", raising=False)
    lib = _user_library(tmp_path / "mine")
    _same_actions(load_for_compile(lib, cache=False), load_for_compile(lib))


def test_warnings_of_the_analysis_are_given_again_from_the_cache(cache_dir, tmp_path, monkeypatch):
    from doodle.app import pipeline

    lib = _user_library(tmp_path / "mine")
    real = pipeline._analysed_clips

    def noisy(*args):
        warnings.warn("a clip says something")
        return real(*args)

    monkeypatch.setattr(pipeline, "_analysed_clips", noisy)
    for _ in range(2):  # cold, then warm (noisy is not called)
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            pipeline.load_for_compile(lib)
        assert [str(w.message) for w in said] == ["a clip says something"]
        assert said[0].category is UserWarning
    assert len(_entries(cache_dir, "clips")) == 1


def test_old_entries_are_pruned_and_nothing_else_touched(cache_dir):
    cache_dir.mkdir()
    (cache_dir / "notes.npz").write_bytes(b"mine")
    for k in range(cache.KEEP + 3):
        assert cache.write("dfas", cache.digest(k), {"x": np.arange(3)})
        os.utime(cache_dir / f"doodle-dfas-{cache.digest(k)}.npz", (1000 + k, 1000 + k))
    cache.prune(cache_dir)
    left = _entries(cache_dir, "dfas")
    assert len(left) == cache.KEEP and cache_dir.joinpath("notes.npz").read_bytes() == b"mine"
    assert {p.stem.split("-")[2] for p in left} == {cache.digest(k) for k in range(3, cache.KEEP + 3)}


# --- forward kinematics kept per clip -------------------------------------------------------------

def test_forward_kinematics_is_kept_read_only_for_clips_and_computed_for_long_motions():
    from retarget.bvh import read_bvh
    from retarget.skeleton import FK_CACHED, Motion, _kinematics, forward_kinematics

    clip = read_bvh(BUILTIN_CLIPS / "walk.bvh")
    first, again = forward_kinematics(clip), forward_kinematics(clip)
    assert first[0] is again[0] and first[1] is again[1]
    assert not first[0].flags.writeable and not first[1].flags.writeable
    fresh = _kinematics(clip)
    assert np.array_equal(first[0], fresh[0]) and np.array_equal(first[1], fresh[1])
    repeat = int(np.ceil((FK_CACHED + 1) / (clip.frames * len(clip.skeleton))))
    long = Motion(clip.skeleton, np.tile(clip.translations, (repeat, 1, 1)), np.tile(clip.rotations, (repeat, 1, 1)),
                  clip.frame_time)
    a, b = forward_kinematics(long), forward_kinematics(long)
    assert a[0] is not b[0] and a[0].flags.writeable and np.array_equal(a[0], b[0])


def test_cache_entries_are_not_synced_to_the_disk_and_outputs_are(cache_dir, tmp_path, monkeypatch):
    """A first run does not wait on the disk for its cache entries (one a power cut empties
    reads as absent and is rebuilt: the "empty" damage above); an output is synced."""
    from doodle.core import files

    synced = []
    monkeypatch.setattr(files.os, "fsync", lambda fd: synced.append(fd))
    assert cache.write("clips", "0" * 64, {"a": np.arange(3)})
    assert synced == [] and np.array_equal(cache.read("clips", "0" * 64)["a"], np.arange(3))
    files.atomic_write(tmp_path / "out.txt", ["kept\n"])
    assert len(synced) == 1 and (tmp_path / "out.txt").read_text() == "kept\n"
