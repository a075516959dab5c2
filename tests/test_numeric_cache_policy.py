"""Compiled code and the cache policy: heyoka's disk cache, stdout, renamed models.

* heyoka runs the object code it finds in its on-disk cache: its cache must be
  the product's checked folder (``<cache>/heyoka``), never heyoka's default
  ``~/.cache/heyoka`` where another user may have planted code under the genuine
  keys; an unsafe folder switches heyoka's disk cache off, with a warning.
* heyoka logs on stdout: nothing of it may reach stdout (``--json``).
* The generated code and the compiled integrators depend on the fields, not on
  the model's name: a renamed model reuses them (counted, not timed).
"""

from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from nilpotent.errors import OptionError
from nilpotent.numeric import bracket_inputs, compile_fields, integrate
from nilpotent.numeric import cache as code_cache

heyoka = pytest.importorskip("heyoka")

from nilpotent.numeric.engines import heyoka_engine, heyoka_setup  # noqa: E402  (needs heyoka)

ROLLER = textwrap.dedent("""\
    name = "{name}"
    coordinates = ["{a}", "{b}", "{c}"]

    [[fields]]
    {a} = "cos({c})"
    {b} = "sin({c})"

    [[fields]]
    {c} = "1"
""")


def _env(home: Path, **extra: str) -> dict[str, str]:
    """The environment of a child process with ``HOME`` at ``home`` and no cache settings."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NILPOTENT_CACHE", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), **extra)
    return env


def _run_python(code: str, env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True,
                          text=True, timeout=300)


# --- the planted object code -----------------------------------------------------------
# A child process compiles, with heyoka's default disk cache ($HOME/.cache/heyoka), the
# integrator the engine builds for the system A, then B (the same with another constant)
# into a second folder, and plants B's object code under A's genuine keys.  Reloading A
# with heyoka's default cache then runs B's code (the control: the plant is live).
_PLANT = textwrap.dedent("""\
    import json, sqlite3, sys
    from pathlib import Path
    import numpy as np, sympy as sp
    import heyoka as hy
    from nilpotent.numeric import bracket_inputs, compile_fields, integrate
    from nilpotent.numeric.engines import heyoka_engine
    from nilpotent.numeric.engines.base import compiled_memo
    heyoka_engine.use_safe_disk_cache = lambda module: None  # heyoka's own default
    x, y, t = sp.symbols("x y t")
    def run(c):
        s = compile_fields((x, y, t), [(sp.cos(t), c * sp.sin(t), 0), (0, 0, 1)],
                           name="planted")
        sol = integrate(s, np.zeros((1, 3)), bracket_inputs(2, 1, 2, [0.3]),
                        engine="heyoka", rtol=1e-12, atol=1e-12)
        compiled_memo(s).clear()
        return sol.final[0].tolist()
    default = Path(str(hy.llvm_state.get_diskcache_path()))
    genuine = run(0.25)
    hy.llvm_state.set_diskcache_path(sys.argv[1])
    other = run(0.5)
    a = sqlite3.connect(default / "cache.db")
    b = sqlite3.connect(Path(sys.argv[1]) / "cache.db")
    keys = [h for (h,) in a.execute("select hash from cache order by last_access")]
    rows = b.execute("select opt_bc, opt_ir, obj from cache order by last_access").fetchall()
    assert len(keys) == len(rows) > 0
    for h, row in zip(keys, rows):
        a.execute("update cache set opt_bc=?, opt_ir=?, obj=? where hash=?", (*row, h))
    a.commit()
    a.close()
    hy.llvm_state.clear_memcache()
    hy.llvm_state.set_diskcache_path(default)
    planted = run(0.25)
    print(json.dumps({"genuine": genuine, "other": other, "planted": planted,
                      "db": str(default / "cache.db")}))
""")

_VICTIM = textwrap.dedent("""\
    import json
    import numpy as np, sympy as sp
    import heyoka as hy
    from nilpotent.numeric import bracket_inputs, compile_fields, integrate
    x, y, t = sp.symbols("x y t")
    s = compile_fields((x, y, t), [(sp.cos(t), 0.25 * sp.sin(t), 0), (0, 0, 1)], name="victim")
    sol = integrate(s, np.zeros((1, 3)), bracket_inputs(2, 1, 2, [0.3]),
                    engine="heyoka", rtol=1e-12, atol=1e-12)
    print(json.dumps({"final": sol.final[0].tolist(),
                      "path": str(hy.llvm_state.get_diskcache_path())}))
""")


def test_object_code_planted_in_heyokas_default_cache_is_never_loaded(tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    other = tmp_path / "other"
    other.mkdir()
    plant = _run_python(_PLANT, _env(home), str(other))
    assert plant.returncode == 0, plant.stderr
    made = json.loads(plant.stdout)
    genuine, planted = np.array(made["genuine"]), np.array(made["planted"])
    # the control: heyoka left to its default folder runs the planted code (B's answer)
    assert np.abs(planted - np.array(made["other"])).max() < 1e-9
    assert np.abs(planted - genuine).max() > 1e-3
    db = Path(made["db"])
    before = db.read_bytes()
    victim = _run_python(_VICTIM, _env(home))
    assert victim.returncode == 0, victim.stderr
    got = json.loads(victim.stdout)
    np.testing.assert_allclose(got["final"], genuine, atol=1e-10)  # its own code ran
    assert Path(got["path"]) == home / ".cache" / "nilpotent" / "heyoka"
    assert db.read_bytes() == before  # not even looked up (a hit rewrites last_access)


def _fresh_heyoka_state(monkeypatch: pytest.MonkeyPatch, folder: Path) -> None:
    monkeypatch.setenv("NILPOTENT_CACHE", str(folder))
    monkeypatch.setattr(heyoka_setup, "_state", {"quiet": True})


@pytest.mark.parametrize("defect", ["mode", "symlink", "owner"])
def test_an_unsafe_heyoka_folder_is_refused_and_its_cache_switched_off(
        tmp_path, monkeypatch, defect):
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    folder = cache / "heyoka"
    folder.mkdir(mode=0o700)
    _fresh_heyoka_state(monkeypatch, cache)
    assert heyoka_setup.use_safe_disk_cache(heyoka) == folder  # safe: used
    assert heyoka.llvm_state.get_diskcache_enabled()
    assert Path(str(heyoka.llvm_state.get_diskcache_path())) == folder
    if defect == "mode":
        os.chmod(folder, 0o777)
        reason = "writable by others"
    elif defect == "symlink":
        (folder / "cache.db").symlink_to(tmp_path / "elsewhere.db")
        reason = "symbolic link"
    else:  # a file of another user in it (the uid seen as another's)
        (folder / "cache.db").write_bytes(b"")
        real = os.stat(folder / "cache.db").st_uid
        real_lstat = os.lstat

        def lstat(path, *args, **kwargs):
            info = real_lstat(path, *args, **kwargs)
            if Path(path).name == "cache.db":
                fields = list(info)
                fields[4] = real + 1  # st_uid
                return os.stat_result(fields)
            return info

        monkeypatch.setattr(os, "lstat", lstat)
        reason = "owned by another user"
    with pytest.warns(RuntimeWarning, match=f"heyoka's disk cache is off: .*{reason}"):
        assert heyoka_setup.use_safe_disk_cache(heyoka) is None
    assert not heyoka.llvm_state.get_diskcache_enabled()
    assert code_cache.library_cache("heyoka")[0] is None


def test_an_unusable_code_cache_switches_heyokas_disk_cache_off(tmp_path, monkeypatch):
    cache = tmp_path / "open"
    cache.mkdir()
    os.chmod(cache, 0o777)
    _fresh_heyoka_state(monkeypatch, cache)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # cache_dir's own warning, and heyoka's
        assert heyoka_setup.use_safe_disk_cache(heyoka) is None
    assert not heyoka.llvm_state.get_diskcache_enabled()
    assert not (cache / "heyoka").exists()


# --- stdout -------------------------------------------------------------------------------
_NOISY = textwrap.dedent("""\
    import os, sys
    import numpy as np, sympy as sp
    from nilpotent.numeric import bracket_inputs, compile_fields, integrate
    from nilpotent.numeric.engines import heyoka_engine, heyoka_setup
    def broken(hy):  # heyoka pointed at a folder it cannot use: it logs warnings
        hy.llvm_state.set_diskcache_path(sys.argv[1] + "/heyoka")
        hy.llvm_state.set_diskcache_enabled(True)
    heyoka_engine.use_safe_disk_cache = broken
    x, y, t = sp.symbols("x y t")
    s = compile_fields((x, y, t), [(sp.cos(t), sp.sin(t), 0), (0, 0, 1)])
    integrate(s, np.zeros((1, 3)), bracket_inputs(2, 1, 2, [0.2]), engine="heyoka")
    with heyoka_setup.stdout_to_stderr():
        os.write(1, b"native text\\n")
    print('{"only": "this"}')
""")


def test_nothing_of_heyoka_reaches_stdout(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")  # heyoka cannot make its folder below a file
    proc = _run_python(_NOISY, _env(tmp_path), str(blocker))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == '{"only": "this"}\n'
    assert "native text" in proc.stderr


def test_json_stdout_is_one_object_when_every_cache_folder_is_unusable(tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    (home / ".cache").write_text("")  # neither nilpotent's nor heyoka's folder can exist
    model = tmp_path / "roller.toml"
    model.write_text(ROLLER.format(name="roller", a="a", b="b", c="phi"))
    proc = subprocess.run(
        [sys.executable, "-m", "nilpotent", "sweep", str(model), "--bracket", "1,2",
         "--samples", "3", "--radius", "0.05", "--json"],
        env=_env(home), capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert isinstance(json.loads(proc.stdout), dict)  # one object, nothing else
    assert "[heyoka" not in proc.stdout and "not using the code cache" in proc.stderr


# --- renamed models -----------------------------------------------------------------------
def _roller(coords: str, name: str, speed: float = 0.3711):
    a, b, c = sp.symbols(coords)
    return compile_fields((a, b, c), [(speed * sp.cos(c), speed * sp.sin(c), 0), (0, 0, 1)],
                          name=name, backend="numpy")


def test_a_renamed_model_reuses_the_generated_code(tmp_path, monkeypatch):
    monkeypatch.setenv("NILPOTENT_CACHE", str(tmp_path))
    one = _roller("x y theta", "zanzibar-first")
    one.field_values(np.zeros(3))
    path = tmp_path / f"np_{one.key}.py"
    text, stamp = path.read_text(), path.stat().st_mtime_ns
    assert "zanzibar" not in text  # the name is in no generated text
    sys.modules.pop(f"nilpotent_generated.np_{one.key}")  # as in a new process
    written = code_cache.STATS["written"]
    two = _roller("a b phi", "zanzibar-second")
    assert two.key == one.key
    two.field_values(np.zeros(3))
    assert code_cache.STATS["written"] == written  # reused, not rewritten
    assert path.read_text() == text and path.stat().st_mtime_ns == stamp


def test_a_renamed_model_shares_the_compiled_integrators(tmp_path, monkeypatch):
    monkeypatch.setenv("NILPOTENT_CACHE", str(tmp_path))
    one = _roller("x y theta", "first", speed=0.6173)
    two = _roller("a b phi", "second", speed=0.6173)
    before = heyoka_engine.COMPILATIONS[one.key]
    inputs = bracket_inputs(2, 1, 2, [0.1])
    a = integrate(one, np.zeros((1, 3)), inputs, engine="heyoka")
    b = integrate(two, np.zeros((1, 3)), inputs, engine="heyoka")
    assert heyoka_engine.COMPILATIONS[one.key] - before == 1  # one build for both
    np.testing.assert_array_equal(a.final, b.final)


def _rows(db: Path) -> int:
    with sqlite3.connect(db) as con:
        return int(con.execute("select count(*) from cache").fetchone()[0])


def test_a_renamed_model_compiles_nothing_in_a_new_process(tmp_path):
    cache = tmp_path / "cache"
    env = _env(tmp_path, NILPOTENT_CACHE=str(cache))
    outputs = []
    listing: list[set[str]] = []
    rows = []
    for name, coords in (("roller", ("a", "b", "phi")), ("wheel", ("u", "v", "w"))):
        model = tmp_path / f"{name}.toml"
        model.write_text(ROLLER.format(name=name, a=coords[0], b=coords[1], c=coords[2]))
        proc = subprocess.run(
            [sys.executable, "-m", "nilpotent", "simulate", str(model), "--bracket", "1,2",
             "--amplitude", "0.1", "--periods", "3", "--json"],
            env=env, capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        outputs.append(json.loads(proc.stdout))
        listing.append({p.name for p in cache.iterdir()})
        rows.append(_rows(cache / "heyoka" / "cache.db"))
    assert rows[0] > 0 and rows[1] == rows[0]  # heyoka found everything in its cache
    assert listing[1] == listing[0]  # no new generated file
    assert outputs[1]["errors"] == outputs[0]["errors"]


# --- fields heyoka cannot express ---------------------------------------------------------
def test_auto_skips_heyoka_for_fields_it_cannot_express_and_heyoka_says_so():
    a, b = sp.symbols("a b")
    system = compile_fields((a, b), [(1, 0), (0, sp.Abs(a - 1))], name="kinked")
    inputs = bracket_inputs(2, 1, 2, [0.1], periods=3)
    start = np.array([[2.0, 0.0]])
    sol = integrate(system, start, inputs)  # long inputs: auto prefers heyoka, if it can
    assert sol.engine != "heyoka" and sol.all_ok
    with pytest.raises(OptionError, match="heyoka engine cannot integrate kinked"):
        integrate(system, start, inputs, engine="heyoka")
