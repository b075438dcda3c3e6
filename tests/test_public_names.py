"""The package's public names: every name in ``navlib.__all__`` resolves, so
``from navlib import *`` works (a moved module once left ``fleet`` behind in it)."""

import importlib

import navlib


def test_every_public_name_resolves():
    for name in navlib.__all__:
        assert getattr(navlib, name) is not None, name


def test_star_import_works():
    namespace: dict = {}
    exec("from navlib import *", namespace)
    assert "NavlibInputError" in namespace
    assert set(navlib.__all__) <= set(namespace)


def test_fleet_lives_under_reports():
    assert importlib.import_module("navlib.reports.fleet") is not None
