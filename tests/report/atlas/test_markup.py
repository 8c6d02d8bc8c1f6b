"""Tests of the HTML the atlas pages share (stiffknots.report.atlas.markup): every given
string is escaped."""

import re

from stiffknots.report.atlas import write_atlas


def test_hostile_names_are_escaped(tmp_path):
    name = '</script><img src=x onerror="alert(1)">'
    idx = write_atlas(tmp_path, [{"name": name, "n": 2, "i": 2, "note": "<b>bold?</b>",
                                  "models": {"bead": {"width": "w </script>",
                                                      "ground": {"shape": "CB<>",
                                                                 "epsilon": 80.0}}}}],
                      thumbnails=False)
    pages = [idx, *(tmp_path / "knots").glob("*.html")]
    assert len(pages) == 2 and all(re.fullmatch(r"[\w.-]+\.html", p.name) for p in pages)
    for p in pages:
        text = p.read_text(encoding="utf-8")
        assert "<img src=x" not in text and "<b>bold?</b>" not in text
        assert "</script><" not in text.replace("</script>\n", "")
