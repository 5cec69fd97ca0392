"""Progress output: counted against the evaluation budget; plain lines when not a terminal."""
from __future__ import annotations

import io

from wavelength_pdf import progress
from wavelength_pdf.optimize import evaluation_budget
from wavelength_pdf.solvers import SOLVERS


def test_budget_is_the_solvers():
    assert evaluation_budget("lbfgsb", grid=[380.0, 780.0]) == 900
    assert evaluation_budget("multistage", grid=[380.0, 780.0],
                             solver_options={"max_evals": 40}) == 40
    # The auto grid is chosen before optimizing (no second, polished refinement any more).
    default = SOLVERS["multistage"].max_evaluations
    assert evaluation_budget("multistage", grid="auto") == default
    assert evaluation_budget("multistage", grid="auto") == evaluation_budget("multistage", grid=[380.0, 780.0])


def test_not_a_terminal_gets_plain_lines():
    out = io.StringIO()
    p = progress.OptimizationProgress("lamp", 100, stream=out, interval=0.0, preparing="compiling")
    for step in range(1, 51):
        p(step, 10.0 / step)
    p.close()
    text = out.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert lines[0] == "lamp: compiling"  # before the first evaluation (test_compile_cache.py)
    assert lines[-1].startswith("lamp: 50/100 evaluations, best J 0.2")
    assert "s left" in lines[2]  # from the second evaluation on


def test_tqdm_bar_off_a_terminal_writes_whole_lines():
    out = io.StringIO()
    with progress.bar(total=3, desc="demo", file=out, interval=0.0) as b:
        for _ in range(3):
            b.update(1)
    text = out.getvalue()
    assert "\r" not in text and "3/3" in text.splitlines()[-1]
