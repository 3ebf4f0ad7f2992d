"""Reproductions of the source documents, one package per document: its scenarios, monitors and report
commands (the plants are library data in :mod:`fdikit.plants`).

* :mod:`fdikit.studies.path1996` — Douglas et al. 1996 (the PATH report): the four-filter Beard–Jones health monitor
  of the vehicle, the comparison of every evaluator on its residuals, and the end-to-end demos.
* :mod:`fdikit.studies.hallouzi2008` — Hallouzi 2008: the target-tracking, B747 and mass–spring–damper benchmarks of
  the multiple-model methods, Table 3.1 and the model-set comparison (Table 3.3), and the report command.
* :mod:`fdikit.studies.vanderploeg2018` — van der Ploeg 2018: the single-track steering-fault cases S1–S8 (Ch. 4).
* :mod:`fdikit.studies.varga2017` — Varga 2017, Chapter 8: the aircraft actuator and air data sensor case studies
  (CS1, CS2) on the reference toolbox's data.
* :mod:`fdikit.studies.varrier2014` — Varrier et al. 2014: the lateral-acceleration sensor fault and the
  ϖ score (§5).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submodules=["path1996", "hallouzi2008", "vanderploeg2018", "varga2017", "varrier2014"],
    submod_attrs={
    },
)
