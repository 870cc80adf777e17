"""Every Python test of scripts/test (the package's, the farm job's and the
Blender add-on's): where CI runs (CI set, as .ci/run is started), a test
that skips for a missing reference (a tool, a sample image, a module) is a
failure naming it, since CI installs every reference; elsewhere the skip
stands, listed by `pytest -rs`."""

import os

import pytest


def in_ci():
    return os.environ.get("CI", "") not in ("", "0", "false")


def _failed_in_ci(report):
    reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
    report.outcome = "failed"
    report.longrepr = f"skipped where CI runs, which installs every reference: {reason}"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if in_ci() and report.skipped and not hasattr(report, "wasxfail"):
        _failed_in_ci(report)


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    outcome = yield
    report = outcome.get_result()
    if in_ci() and report.skipped:
        _failed_in_ci(report)
