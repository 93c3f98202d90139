"""The documentation's pages: every guide shows a figure made by its own command when the
docs are built, equations become MathML (no script, no network), and the check of the built
pages catches Markdown and math that did not render."""

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
GUIDES = ROOT / "docs" / "guides"
#: Reference pages among the guides: looked up, not walked through, and so without a figure (the
#: runs' machinery; the maintainers' checklists of files to touch).
REFERENCES = {"runs-reference.md", "maintainers.md"}
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
from quadcosim_docs import mathml, unrendered  # noqa: E402

_MATH = re.compile(r"\$\$(.+?)\$\$|(?<![\\$])\$([^$`\n]+?)\$", re.S)


def test_every_guide_shows_a_figure_its_own_command_makes_at_build_time():
    guides = sorted(p for p in GUIDES.glob("*.md") if p.name not in REFERENCES)
    assert len(guides) >= 12
    without = [p.name for p in guides if "```{quadcosim-run}" not in p.read_text()]
    assert without == []


def test_every_equation_of_the_pages_becomes_mathml_without_tex():
    equations = [a or b for page in (ROOT / "docs").rglob("*.md") if "_build" not in page.parts
                 for a, b in _MATH.findall(page.read_text())]
    assert len(equations) >= 40  # 50 inline and displayed when written: the pattern finds them all
    for tex in equations:
        shown = mathml(tex, display=False)
        assert shown.startswith("<math") and "\\" not in shown and "merror" not in shown, tex
    assert 'display="block"' in mathml(r"IR = a\,r + b", display=True)


@pytest.mark.parametrize("tex, told", [(r"\begin{bmatrix} a", "MissingEndError"), (r"\foo x", r"\foo unknown")])
def test_tex_the_converter_cannot_read_is_refused_naming_the_equation(tex, told):
    with pytest.raises(ValueError, match="cannot be converted to MathML") as refused:
        mathml(tex, display=False)
    assert told in str(refused.value) and repr(tex) in str(refused.value)


@pytest.mark.parametrize("html, fault", [
    ("<article><p>the `run` command</p></article>", "`"),
    ("<article><p>&lt;!-- findings:speed.x --&gt;1.1</p></article>", "findings"),
    (r"<article><p>the filter \(\dot q = q\)</p></article>", "\\("),
    ("<article><p>$$IR = a r + b$$</p></article>", "$$"),
])
def test_the_built_pages_check_names_what_did_not_render(html, fault):
    faults = unrendered(html)
    assert len(faults) >= 1 and fault in faults[0]


def test_the_built_pages_check_passes_code_mathml_and_a_clean_page():
    clean = ("<article><p>the <code>`run`</code> command, "
             + mathml(r"\dot q = \frac{1}{2} q \otimes \omega", display=False) + "</p><pre>$$ \\( `x`</pre></article>")
    assert unrendered(clean) == []
