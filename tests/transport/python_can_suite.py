"""python-can's own back-to-back tests, for the installed python-can version, from its sdist.

python-can's ``test/back2back_test.py`` (``Back2BackTestCase``: two buses on one channel,
each sending to the other) is not in its wheel. :func:`load_back2back` returns that
module for exactly the installed version: the first call fetches the version's source
distribution with pip (``pip download python-can==<version> --no-deps --no-binary
:all:``; pip checks the archive against the index's hash), takes ``test/__init__.py``,
``test/back2back_test.py`` and every module of python-can's test folder that it imports
(its relative imports, found by parsing it, recursively), and keeps them as a package in
a cache directory; later calls import them from there. Nothing of python-can is kept in
this repository.

Cache directory: ``$THRUSTER_HIL_TEST_CACHE`` if set, else ``<sys.prefix>/var/cache/
thruster-hil``: inside the virtual environment the tests run in, next to the python-can
it matches (a new venv fetches again), and visible wherever that venv is (CI's SocketCAN
guest has no network but sees the host's venv). ``python -m
tests.transport.python_can_suite`` fetches ahead (``.ci/run`` does, in its install stage)
and prints where the files are.

Failure: no silent skip. If the files cannot be had, a RuntimeError says why (pip's own
last lines) and how to fetch them; a test module that loads the suite at import then fails
to collect.
"""

from __future__ import annotations

import ast
import hashlib
import importlib
import importlib.metadata
import importlib.util
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from types import ModuleType

DISTRIBUTION = "python-can"
CACHE_ENV = "THRUSTER_HIL_TEST_CACHE"
SUITE_MODULE = "back2back_test"
PACKAGE_INIT = "__init__"
FETCH_TIMEOUT_S = 600.0
PIP_ERROR_TAIL_LINES = 15
COMPLETE_MARK = "SOURCE"  # written last: names the sdist and its sha256


def installed_version() -> str:
    """The installed python-can's version, e.g. ``4.6.1``."""
    return importlib.metadata.version(DISTRIBUTION)


def cache_dir() -> Path:
    """Where fetched test files are kept (see the module docstring)."""
    configured = os.environ.get(CACHE_ENV)
    if configured:
        return Path(configured)
    return Path(sys.prefix) / "var" / "cache" / "thruster-hil"


def package_name(version: str) -> str:
    """The import name of the cached test package of ``version``."""
    return "python_can_tests_" + "".join(c if c.isalnum() else "_" for c in version)


def fetch(version: str | None = None) -> Path:
    """The directory of python-can's test package for ``version`` (default: installed),
    fetched into the cache first if it is not there. Raises RuntimeError saying why."""
    version = version or installed_version()
    target = cache_dir() / package_name(version)
    if (target / COMPLETE_MARK).is_file():
        return target
    try:
        cache_dir().mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=cache_dir(), prefix="fetch-") as tmp:
            sdist = _download(version, Path(tmp))
            staged = Path(tmp) / target.name
            _extract_suite(sdist, staged)
            digest = hashlib.sha256(sdist.read_bytes()).hexdigest()
            (staged / COMPLETE_MARK).write_text(f"{sdist.name} sha256 {digest}\n")
            try:
                staged.rename(target)
            except OSError:
                if not (target / COMPLETE_MARK).is_file():  # not another fetch's
                    raise
    except OSError as exc:
        raise RuntimeError(f"cannot keep python-can's test files in {target}: {exc}; "
                               f"set {CACHE_ENV} to a writable directory") from exc
    return target


def _download(version: str, into: Path) -> Path:
    """python-can's sdist of ``version`` downloaded into ``into`` by pip."""
    cmd = [sys.executable, "-m", "pip", "download", f"{DISTRIBUTION}=={version}", "--no-deps",
           "--no-binary", ":all:", "--dest", str(into), "--quiet",
           "--disable-pip-version-check"]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=FETCH_TIMEOUT_S,
                              check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise RuntimeError(_advice(version, f"{' '.join(cmd)}: {exc}")) from exc
    sdists = sorted(into.glob("*.tar.gz"))
    if done.returncode != 0 or len(sdists) != 1:
        tail = "\n".join((done.stderr or done.stdout).splitlines()[-PIP_ERROR_TAIL_LINES:])
        raise RuntimeError(_advice(version, f"{' '.join(cmd)} exited {done.returncode}, "
                                                f"found {len(sdists)} sdists:\n{tail}"))
    return sdists[0]


def _advice(version: str, what: str) -> str:
    return (f"python-can {version}'s back-to-back tests are not in its wheel and could not be "
            f"fetched from its source distribution ({what}). They need PyPI once: run "
            f"'python -m tests.transport.python_can_suite' where PyPI is reachable, or set "
            f"{CACHE_ENV} to a directory that holds them.")


def _extract_suite(sdist: Path, staged: Path) -> None:
    """``test/__init__.py``, ``test/back2back_test.py`` and the test modules it imports
    (relatively, recursively) from ``sdist`` into the package directory ``staged``."""
    staged.mkdir()
    with tarfile.open(sdist, "r:gz") as tar:
        names = tar.getnames()
        top = names[0].split("/", 1)[0]
        wanted = [PACKAGE_INIT, SUITE_MODULE]
        done: set[str] = set()
        while wanted:
            module = wanted.pop()
            if module in done:
                continue
            member = f"{top}/test/{module}.py"
            if member not in names:
                raise RuntimeError(f"{sdist.name} has no {member}")
            handle = tar.extractfile(member)
            if handle is None:
                raise RuntimeError(f"{sdist.name}: {member} is not a file")
            source = handle.read()
            (staged / f"{module}.py").write_bytes(source)
            done.add(module)
            wanted += _relative_imports(source)


def _relative_imports(source: bytes) -> list[str]:
    """Modules a test module imports from its own package (``from .config import ...``)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.append(node.module.split(".")[0])
            else:
                out += [alias.name for alias in node.names]
    return out


def load_back2back(version: str | None = None) -> ModuleType:
    """python-can's ``back2back_test`` module of ``version`` (default: the installed one),
    imported from the cache (fetched first if needed). Raises RuntimeError saying why."""
    version = version or installed_version()
    directory = fetch(version)
    name = package_name(version)
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, directory / f"{PACKAGE_INIT}.py", submodule_search_locations=[str(directory)]
        )
        if spec is None or spec.loader is None:
            raise RuntimeError(f"cannot import python-can's test package from {directory}")
        package = importlib.util.module_from_spec(spec)
        sys.modules[name] = package
        spec.loader.exec_module(package)
    return importlib.import_module(f"{name}.{SUITE_MODULE}")


def main() -> None:
    """Fetch python-can's test files for the installed version; print their directory."""
    try:
        print(fetch())
    except RuntimeError as exc:
        sys.exit(f"error: {exc}")


if __name__ == "__main__":
    main()
