import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: heyoka keeps compiled code in an on-disk cache (by default ~/.cache/heyoka, up to 20 GiB), and every new
#: process that compiles reads through all of it first (README, "What a run writes": 4.9 s for 7.8 GiB).
#: One run of this suite adds ~0.6 GiB of shapes no user scene needs: it gets a cache of its own, which
#: its subprocesses (the CLI tests) inherit, capped at TEST_CACHE_LIMIT (heyoka evicts the least recently
#: used). HEYOKA_CACHE_DIR, heyoka's own variable, is read when heyoka is imported: set here, before any
#: test module imports heyroll. A HEYOKA_CACHE_DIR already set is kept.
TEST_CACHE_LIMIT = 2 * 2**30
OWN_CACHE = "HEYOKA_CACHE_DIR" not in os.environ  # (a cache the user chose keeps its own limit: review)
os.environ.setdefault("HEYOKA_CACHE_DIR", str(
    Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "heyroll-tests" / "heyoka"))


def pytest_configure(config):
    import heyoka

    if OWN_CACHE and heyoka.llvm_state.get_diskcache_enabled() and \
            heyoka.llvm_state.get_diskcache_limit() > TEST_CACHE_LIMIT:
        heyoka.llvm_state.set_diskcache_limit(TEST_CACHE_LIMIT)
EXAMPLE = ROOT / "examples" / "disk_and_ring.toml"


def arc_chain_segments() -> str:
    """The [[track.segments]] tables of examples/arc_chain.toml (a line, a concave and a convex arc)."""
    text = (ROOT / "examples" / "arc_chain.toml").read_text()
    start = text.index("[[track.segments]]")
    return text[start:text.index("[[bodies]]")].strip() + "\n"


@pytest.fixture
def example_text() -> str:
    return EXAMPLE.read_text(encoding="utf-8")


def scene_text(bodies: str, *, track: str = 'type = "circle"\nradius = 1.0', extra: str = "") -> str:
    """A scene file with the given [[bodies]] blocks."""
    return f"g = 9.81\n{extra}\n[track]\n{track}\n{bodies}"


def body(shape="solid_sphere", radius="0.1", mass="1.0", phi="0.0", dphi="0.0", extra="") -> str:
    lines = ["[[bodies]]", f'shape = "{shape}"', f"radius = {radius}"]
    if mass is not None:
        lines.append(f"mass = {mass}")
    lines += [f"phi = {phi}", f"dphi = {dphi}"]
    if extra:
        lines.append(extra)
    return "\n".join(lines) + "\n"


@pytest.fixture(autouse=True)
def _handlers_built_per_test():
    """The engine caches a mode's event handlers between runs (simulation.driver._handlers): a test that
    replaces a handler factory (monkeypatch) must not meet handlers another test built, nor leave its own."""
    from heyroll.simulation.driver import forget_handlers

    forget_handlers()
    yield
    forget_handlers()
