"""Shared fixtures: small circuits and drives used across the test suite."""

import matplotlib
import pytest

matplotlib.use("Agg")


# ------------------------------------------------------------------ plots: labels and units
def _labelled(label: str, categorical: bool) -> bool:
    """A quantity and its unit, "speed [rad/s]" or "magnitude (dB)"; a categorical axis
    (names on its ticks) needs only a name."""
    import re
    label = label.strip()
    if categorical:
        return bool(label)
    m = re.search(r"[\[(]([^\])]+)[\])]\s*$", label) or re.search(r"[\[(]([^\])]+)[\])]",
                                                                  label)
    return bool(m) and bool(label[:m.start()].strip())


def figure_label_problems(fig) -> list[str]:
    """What a figure lacks: each axes with data needs an x and a y label with a quantity
    and a unit (or a labelled axes sharing that axis), and each labelled line a legend
    entry somewhere in the figure."""
    from matplotlib.category import UnitData
    problems = []
    axes = [a for a in fig.axes if a.get_visible()
            and (a.lines or a.collections or a.patches or a.images)]
    legends = [t.get_text() for lg in fig.legends for t in lg.get_texts()]
    for a in fig.axes:
        if a.get_legend() is not None:
            legends += [t.get_text() for t in a.get_legend().get_texts()]
    for i, a in enumerate(axes):
        for which in ("x", "y"):
            axis = getattr(a, f"{which}axis")
            categorical = isinstance(axis.units, UnitData)
            shared = getattr(a, f"get_shared_{which}_axes")()
            labels = [getattr(b, f"get_{which}label")() for b in axes
                      if b is a or shared.joined(a, b)]
            if not any(_labelled(t, categorical) for t in labels):
                problems.append(f"axes {i} ({a.get_title() or fig.get_suptitle()!r}): "
                                f"{which} label {getattr(a, f'get_{which}label')()!r} "
                                "lacks a quantity or a unit")
        for artist in [*a.lines, *a.collections, *a.patches]:
            lab = artist.get_label()
            if lab and not lab.startswith("_") and lab not in legends:
                problems.append(f"axes {i}: '{lab}' has no legend entry")
    return sorted(set(problems))


class SavedFigures(list):
    """The figures saved during a test; :meth:`problems` lists their missing labels."""

    def problems(self) -> list[str]:
        return [f"figure {k} ({f.get_suptitle()!r}): {p}" for k, f in enumerate(self)
                for p in figure_label_problems(f)]


@pytest.fixture
def saved_figures(monkeypatch):
    """Every matplotlib figure saved while the test runs (checked as saved)."""
    from matplotlib.figure import Figure
    figures = SavedFigures()
    save = Figure.savefig

    def recording(self, *args, **kwargs):
        figures.append(self)
        return save(self, *args, **kwargs)
    monkeypatch.setattr(Figure, "savefig", recording)
    return figures


# ---------------------------------------------------------------- logging: left as found
def _package_loggers() -> list:
    """The ``mechatron`` logger and every logger below it that exists now."""
    import logging
    loggers = logging.Logger.manager.loggerDict
    return [logging.getLogger("mechatron")] + [
        logger for name, logger in list(loggers.items())
        if name.startswith("mechatron.") and isinstance(logger, logging.Logger)]


@pytest.fixture(autouse=True)
def _logging_left_as_found():
    """Each test leaves the package's loggers (level, handlers, flags), the root logger's
    level and ``logging.disable`` as it found them. The docs' examples run in this process
    (tests/test_docs.py), and one of them quiets the ``mechatron`` logger as a user would:
    left so, it hid the warnings that later tests read with ``caplog``. (The root logger's
    handlers are pytest's own, added and removed around each phase: not touched.)"""
    import logging
    root = logging.getLogger()
    saved = [(logger, logger.level, logger.disabled, logger.propagate,
              list(logger.handlers)) for logger in _package_loggers()]
    known = {id(logger) for logger, *_ in saved}
    root_level, disabled = root.level, logging.root.manager.disable
    yield
    for logger, level, off, propagate, handlers in saved:
        logger.setLevel(level)
        logger.disabled, logger.propagate, logger.handlers[:] = off, propagate, handlers
    for logger in _package_loggers():       # made during the test: as new again
        if id(logger) not in known:
            logger.setLevel(logging.NOTSET)
            logger.disabled, logger.propagate, logger.handlers[:] = False, True, []
    root.setLevel(root_level)
    logging.disable(disabled)


# ------------------------------------------------------------------ test order: reshuffled
def pytest_addoption(parser):
    parser.addoption(
        "--order-seed", type=int, default=None, metavar="SEED",
        help="run the test modules in an order shuffled by SEED, each module's tests "
             "reversed: a test that passes only after (or before) another fails")


def pytest_collection_modifyitems(config, items):
    seed = config.getoption("--order-seed")
    if seed is None:
        return
    import random
    modules: dict = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::")[0], []).append(item)
    order = list(modules)
    random.Random(seed).shuffle(order)
    items[:] = [item for module in order for item in reversed(modules[module])]
