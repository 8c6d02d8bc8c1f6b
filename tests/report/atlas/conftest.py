"""Fixtures of the tests of the atlas pages: six synthetic knots, their atlas written once
(thumbnails and all), and readers of its index table and of the JSON in its pages."""

import json
import re
from html.parser import HTMLParser

import pytest

from atlas_support import synthetic_families, synthetic_knots
from stiffknots.report.atlas import write_atlas


class _Rows(HTMLParser):
    """The rows of the knot table: their attributes and the text and attributes of each cell."""

    def __init__(self):
        super().__init__()
        self.rows, self._in_body, self._cell = [], False, None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table" and a.get("id") == "knots":
            self._in_table = True
        if tag == "tbody" and getattr(self, "_in_table", False):
            self._in_body = True
        elif tag == "tr" and self._in_body:
            self.rows.append({"attrs": a, "cells": []})
        elif tag == "td" and self._in_body:
            self._cell = {"attrs": a, "text": "", "spans": {}, "links": [], "imgs": []}
            self.rows[-1]["cells"].append(self._cell)
            self._span = None
        elif self._cell is not None:
            if tag == "span" and "m" in (a.get("class") or "").split():
                self._span = a["class"].split()[1][2:]  # "m m-bead" -> "bead"
                self._cell["spans"][self._span] = ""
            elif tag == "a":
                self._cell["links"].append(a.get("href"))
            elif tag == "img":
                self._cell["imgs"].append(a.get("src"))

    def handle_endtag(self, tag):
        if tag == "tbody":
            self._in_body = False
            self._in_table = False
        elif tag == "td":
            self._cell = None
        elif tag == "span":
            self._span = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell["text"] += data
            if self._span is not None:
                self._cell["spans"][self._span] += data


COLS = ["thumb", "knot", "n_c", "n", "i", "bounds", "thin", "shape", "eps", "width", "converged",
        "metastable", "dmin", "families"]


def _read_rows(text):
    p = _Rows()
    p.feed(text)
    return [(r["attrs"], dict(zip(COLS, r["cells"], strict=True))) for r in p.rows]


@pytest.fixture(scope="session")
def read_rows():
    """The rows of the knot table of an index page: (the row's attributes, {column: cell})
    with the columns of ``COLS``; a cell has its ``text``, ``spans`` (per model), ``links``,
    ``imgs`` and ``attrs``."""
    return _read_rows


@pytest.fixture(scope="session")
def knots():
    return synthetic_knots()


@pytest.fixture(scope="session")
def atlas(tmp_path_factory, knots):
    out = tmp_path_factory.mktemp("atlas")
    index = write_atlas(out, knots, families=synthetic_families(), title="Test atlas",
                        meta={"budget": "synthetic"})
    return index


@pytest.fixture(scope="session")
def rows(atlas):
    return {a["data-name"]: cells for a, cells in _read_rows(atlas.read_text(encoding="utf-8"))}


def _script_json(text, element_id):
    m = re.search(rf'<script type="application/json" id="{element_id}">(.*?)</script>', text,
                  re.S)
    assert m, f"no {element_id} in the page"
    return json.loads(m.group(1))


@pytest.fixture(scope="session")
def script_json():
    """The JSON of the ``<script type="application/json" id=...>`` element of a page."""
    return _script_json
