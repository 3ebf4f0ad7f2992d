"""A progress bar for long loops: rich's, or nothing, behind one ``tick(description, steps=1)`` callback.

Written by hand because the long studies want the same three lines around ``rich.progress.Progress``
(start, advance with a description, stop) and a silent variant with the same call.
"""

from __future__ import annotations

__all__ = ["progress_bar"]


class progress_bar:  # noqa: N801 - used like a function: ``with progress_bar(...) as tick``
    """``with progress_bar(show, total, title) as tick: ... tick("done x")`` — a rich bar, or nothing.

    Parameters
    ----------
    show : bool
        Draw the bar (False: ``tick`` does nothing).
    total : int
        Steps in all.
    title : str, optional
        The bar's first description.

    Examples
    --------
    >>> with progress_bar(False, 3) as tick:
    ...     for k in range(3):
    ...         tick(f"step {k}")
    """

    def __init__(self, show: bool, total: int, title: str = "") -> None:
        self.show, self.total, self.title = show, total, title

    def __enter__(self):
        if not self.show:
            return lambda *a, **k: None
        from rich.progress import Progress

        self.bar = Progress()
        self.bar.start()
        task = self.bar.add_task(self.title, total=self.total)
        return lambda desc, n=1: self.bar.update(task, advance=n, description=desc)

    def __exit__(self, *exc) -> bool:
        if self.show:
            self.bar.stop()
        return False
