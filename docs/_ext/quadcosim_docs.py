"""Sphinx extension of the quadcosim documentation.

- ``quadcosim-run``: a directive that runs the ``quadcosim`` command it shows (in-process, into
  ``docs/_generated/runs/<hash>/``, reused while its ``metrics.json`` is there) and shows the
  command, the figure it wrote and the metrics named, so that every figure of the lab
  walk-through is made by the command beside it.
- the FMUs' variable tables, generated from ``fmus/<Model>/variables.py`` into
  ``docs/_generated/fmu_variables.md`` when the build starts.
- the notebooks: ``notebooks/*.py`` (jupytext's percent format) written as
  ``docs/_generated/notebooks/*.ipynb`` when the build starts, for myst-nb to execute (with its
  cache) and render with their figures.
- the math renderer ``mathml``: each equation converted to MathML when the page is built
  (``latex2mathml``), which browsers draw with no script and no network; MathJax from a CDN
  showed raw TeX offline.
- a check of the built pages: Markdown that did not render (a literal backtick in the text, a
  findings marker shown as text) or math left as TeX is a warning, so ``sphinx -W`` fails on
  it. A line that starts with a findings marker is read by Markdown as raw HTML, and its
  backticks then show.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import re
import shlex
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive, directives

HERE = Path(__file__).resolve().parent.parent
GENERATED = HERE / "_generated"


DONE = ".docs-done"  # written into a command's folder once it and its follow-up succeeded


def _call(argv: list[str]) -> None:
    """``quadcosim ARGV``, or ``python -m MODULE ARGS`` when ARGV starts so, in this process; its
    output shown only if it fails."""
    import importlib

    if argv[:2] == ["python", "-m"]:
        main, shown = importlib.import_module(argv[2]).main, argv[3:]
    else:
        from quadcosim.main import main

        shown = argv
    told = io.StringIO()
    with contextlib.redirect_stdout(told), contextlib.redirect_stderr(told):
        code = main(shown)
    if code != 0:
        raise RuntimeError(f"{_shown_command(argv)} exited {code}:\n{told.getvalue()[-2000:]}")


def _shown_command(argv_or_text) -> str:
    """The command as a page shows it: ``quadcosim ...``, or ``python -m ...`` as it is."""
    text = argv_or_text if isinstance(argv_or_text, str) else shlex.join(argv_or_text)
    return text if text.startswith("python -m ") else f"quadcosim {text}"


def _run(command: str, then: str | None = None, name: str | None = None, setup: str | None = None) -> Path:
    """The folder of ``quadcosim COMMAND``'s results (its ``--out``), running it first if not
    done yet, after ``setup`` (a command that makes its inputs: ``log example logs``), then
    ``then`` (a command with ``{out}`` standing for that folder); ``name``: the folder's own
    name, as figure titles show it (``k-sweep``). The commands run in the folder above it, so
    that the relative paths a page shows (``logs/example-a.log``) are found."""
    import shutil

    import matplotlib

    matplotlib.use("Agg")  # this process draws into files (MPLBACKEND names the notebooks' kernels' backend)
    key = f"{command}\n{then}\n{name}" + (f"\n{setup}" if setup else "")  # the older pages' folders kept
    out = GENERATED / "runs" / hashlib.sha256(key.encode()).hexdigest()[:16]
    out = out / name if name else out
    metrics = out / "metrics.json"
    done = (out / DONE).is_file() or (then is None and setup is None and metrics.is_file()
                                       and json.loads(metrics.read_text()).get("status") == "completed")
    if not done:
        shutil.rmtree(out.parent if name else out, ignore_errors=True)
        out.mkdir(parents=True)  # a folder as --out (diagram's takes diagram.png in it)
        with contextlib.chdir(out.parent if name else out):
            if setup:
                _call(shlex.split(setup))
            argv = shlex.split(command)
            _call([*argv, "--out", str(out)] + (["--overwrite"] if argv[0] == "run" else []))
            if then:
                _call(shlex.split(then.format(out=shlex.quote(str(out)))))
        (out / DONE).write_text(f"{setup or ''}\n{command}\n{then or ''}\n")
    return out


def _shown(value, digits: int | None = None) -> str:
    from quadcosim.scenarios.shown import MEASURED_DIGITS, shown

    return shown(value, digits or MEASURED_DIGITS)


class QuadcosimRun(Directive):
    """``quadcosim-run``: the argument is the command after ``quadcosim`` (its ``--out`` is added);
    options ``figure`` (a file the run writes, ``roll_pitch.png`` by default; several,
    comma-separated, shown one below the other), ``metrics``
    (comma-separated names of ``metrics.json`` to print), ``then`` (a second command on the
    results, ``{out}`` standing for their folder: ``plot {out} Setpoint.theta_d Quadrotor.theta
    --tracking``; ``python -m MODULE ...`` runs that module's ``main``), ``setup`` (a command run
    first, in the folder the commands run in: ``log example logs``) and ``out`` (the folder as
    the page shows it, ``results/NAME``; shown with ``then`` or ``setup``)."""

    required_arguments = 1
    final_argument_whitespace = True
    option_spec = {"figure": directives.unchanged, "metrics": directives.unchanged, "then": directives.unchanged,
                   "out": directives.unchanged, "setup": directives.unchanged}

    def run(self):
        command, then, setup = self.arguments[0], self.options.get("then"), self.options.get("setup")
        folder = self.options.get("out", "results/run")
        out = _run(command, then, Path(folder).name if then or setup else None, setup)
        if then or setup:
            lines = [_shown_command(setup)] if setup else []
            lines.append(f"quadcosim {command} --out {folder}")
            lines += [_shown_command(then.format(out=folder))] if then else []
            text = "\n".join(lines)
        else:
            text = f"quadcosim {command}"
        shown = [nodes.literal_block(text=text, language="sh")]
        names = [n.strip() for n in self.options.get("metrics", "").split(",") if n.strip()]
        if names:
            metrics = json.loads((out / "metrics.json").read_text())
            text = "; ".join(f"{name} = {_shown(metrics.get(name))}" for name in names)
            shown.append(nodes.paragraph(text=f"Measured by this command: {text}."))
        for figure in (f.strip() for f in self.options.get("figure", "roll_pitch.png").split(",")):
            path = out / figure
            if not path.is_file():
                raise self.error(f"quadcosim {command} wrote no {figure}")
            shown.append(nodes.image(uri="/" + path.relative_to(HERE).as_posix(),
                                     alt=f"{figure} of quadcosim {command}", width="100%"))
        return shown


def _variable_tables(app):
    """``_generated/fmu_variables.md``: every FMU's variable table (from its ``variables.py``)."""
    from quadcosim.fmus import MODELS
    from quadcosim.fmus.build import table

    lines = ["# The FMUs' variables", "",
             "Generated from each model's `fmus/<Model>/variables.py` (the source of its "
             "`modelDescription.xml` and C accessors): their start values are inputs.", "",
             "<!-- inputs -->", ""]
    for model in MODELS:
        lines += [f"## {model}", "", "| name | causality | unit | start | description |", "|---|---|---|---|---|"]
        for variable in table(model).variables:
            from quadcosim.scenarios.shown import PARAMETER_DIGITS

            start = "" if variable.start is None else _shown(variable.start, PARAMETER_DIGITS)
            description = str(variable.description).replace("|", "\\|")
            lines.append(f"| `{variable.name}` | {variable.causality} | {variable.unit or ''} | {start} | "
                         f"{description} |")
        lines.append("")
    lines += ["<!-- /inputs -->", ""]
    GENERATED.mkdir(exist_ok=True)
    target = GENERATED / "fmu_variables.md"
    text = "\n".join(lines)
    if not target.is_file() or target.read_text() != text:
        target.write_text(text)


def _registry_tables(app):
    """``_generated/registries.md``: the estimators, interference models, autopilots and scenarios,
    read from their registries (:mod:`quadcosim.scenarios.registries`)."""
    from quadcosim.scenarios.registries import sensor_table, tables

    (GENERATED / "tables").mkdir(parents=True, exist_ok=True)
    # the page of the sets, and the table of FMUs that docs/guides/fmus.md includes
    pages = {GENERATED / "registries.md": tables(), GENERATED / "tables" / "sensors.md": sensor_table()}
    for target, text in pages.items():
        if not target.is_file() or target.read_text() != text:
            target.write_text(text)


NOTEBOOKS = HERE.parent / "notebooks"
#: The packages a notebook calls: an execution older than their newest source is stale.
PACKAGES = ("fmus", "orchestrator", "estimators", "calibration", "scenarios", "benchmarks")


def newest_source(root: Path = HERE.parent) -> float:
    """The newest modification time (s since the epoch) of the packages' Python sources."""
    return max(p.stat().st_mtime for package in PACKAGES for p in (root / package).rglob("*.py"))


def _notebooks(app):
    """``_generated/notebooks/NAME.ipynb`` of each ``notebooks/NAME.py``, rewritten only when it
    changes (so that Sphinx and myst-nb's cache see an unchanged notebook as unchanged), and the
    cached executions older than the packages' sources dropped: myst-nb's cache knows only a
    notebook's own code, and a change of the package must run the notebooks again."""
    import calendar

    import jupytext
    from jupyter_cache import get_cache

    cache_path = Path(app.config.nb_execution_cache_path)
    if cache_path.is_dir():
        cache, newest = get_cache(cache_path), newest_source()
        for record in cache.list_cache_records():
            if calendar.timegm(record.created.utctimetuple()) <= newest:
                cache.remove_cache(record.pk)

    target = GENERATED / "notebooks"
    target.mkdir(parents=True, exist_ok=True)
    for source in sorted(NOTEBOOKS.glob("*.py")):
        text = jupytext.writes(jupytext.read(source), fmt="ipynb")
        path = target / f"{source.stem}.ipynb"
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)


def mathml(tex: str, display: bool) -> str:
    """The MathML of a LaTeX equation, as the pages carry it.

    Parameters
    ----------
    tex : str
        The equation, without its ``$`` delimiters.
    display : bool
        A displayed equation (a block of its own) rather than one in the text.

    Returns
    -------
    str
        A ``<math>`` element.

    Raises
    ------
    ValueError
        TeX the converter cannot read, naming the equation.
    """
    from latex2mathml.converter import convert

    try:
        shown = convert(tex.strip(), display="block" if display else "inline")
    except Exception as error:  # the converter raises its own exception types
        raise ValueError(f"equation {tex!r} cannot be converted to MathML ({type(error).__name__}: {error}); "
                         "write it with commands latex2mathml knows") from None
    unknown = re.findall(r"\\[A-Za-z]+", shown)  # a command it does not know is kept as its TeX
    if unknown:
        raise ValueError(f"equation {tex!r} cannot be converted to MathML: {', '.join(unknown)} unknown to "
                         "latex2mathml; write it with commands it knows")
    return shown


def _visit_math(translator, node):
    translator.body.append(translator.starttag(node, "span", "", CLASS="math notranslate nohighlight"))
    translator.body.append(mathml(node.astext(), display=False) + "</span>")
    raise nodes.SkipNode


def _visit_displaymath(translator, node):
    translator.body.append(translator.starttag(node, "div", CLASS="math notranslate nohighlight"))
    if node.get("number"):
        translator.body.append(f'<span class="eqno">({node["number"]})</span>')
    for part in node.astext().split("\n\n"):  # one block may hold several equations
        if part.strip():
            translator.body.append(mathml(part, display=True))
    translator.body.append("</div>\n")
    raise nodes.SkipNode


_VERBATIM = re.compile(r"<(pre|code|script|style|kbd|tt|textarea)\b.*?</\1>", re.S | re.I)
_COMMENT = re.compile(r"<!--.*?-->", re.S)
_TAG = re.compile(r"<[^>]+>")
_ARTICLE = re.compile(r"<article\b.*?</article>", re.S)


def unrendered(html: str) -> list[str]:
    """What of a built page's text is Markdown that did not render: each literal backtick, each
    findings marker shown as text and each equation left as TeX (``\\(``, ``\\[``, ``$$``), with the
    words around it.

    Parameters
    ----------
    html : str
        A page as Sphinx wrote it.

    Returns
    -------
    list of str
        One excerpt per fault; empty for a clean page.
    """
    article = _ARTICLE.search(html)
    text = _TAG.sub(" ", _COMMENT.sub(" ", _VERBATIM.sub(" ", article.group(0) if article else html)))
    faults = []
    for match in re.finditer(r"`|&lt;!--\s*/?findings|\\\(|\\\[|\$\$", text):
        excerpt = " ".join(text[max(0, match.start() - 60):match.end() + 60].split())
        faults.append(excerpt.replace("&lt;", "<").replace("&gt;", ">"))
    return faults


def _check_rendered(app, exception):
    """Warn (an error under ``-W``) on every page whose text holds unrendered Markdown."""
    if exception is not None or app.builder.format != "html":
        return
    from sphinx.util import logging

    logger = logging.getLogger(__name__)
    for page in sorted(Path(app.outdir).rglob("*.html")):
        if {"_modules", "_static", "_sources"} & set(page.relative_to(app.outdir).parts):
            continue
        for fault in unrendered(page.read_text(encoding="utf-8", errors="replace")):
            logger.warning(f"{page.relative_to(app.outdir)}: Markdown or math not rendered (a line that starts "
                           f"with a findings marker is raw HTML to Markdown): ...{fault}...")


def setup(app):
    """Register the directive, the generated pages and the check of the built pages."""
    app.add_directive("quadcosim-run", QuadcosimRun)
    app.add_html_math_renderer("mathml", (_visit_math, None), (_visit_displaymath, None))
    app.connect("builder-inited", _variable_tables)
    app.connect("builder-inited", _registry_tables)
    app.connect("builder-inited", _notebooks)
    app.connect("build-finished", _check_rendered)
    return {"parallel_read_safe": False, "version": "1"}
