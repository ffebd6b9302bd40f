"""The one progress bar, used as a ``progress(done, total)`` callback as well."""

import io

from mechcirc.progress import Progress


class Tty(io.StringIO):
    def isatty(self):
        return True


def test_progress_as_callback_learns_the_total_and_counts_to_it():
    out = Tty()
    with Progress(0, "sley", stream=out, delay=0) as bar:
        bar(1, 3)
        assert (bar.done, bar.total) == (1, 3)
        bar(3, 3)
        assert (bar.done, bar.total) == (3, 3)
    text = out.getvalue()
    assert text.startswith("\rsley [") and "1/3" in text
    assert "3/3" in text and text.endswith("\n")


def test_progress_callback_is_silent_off_a_terminal():
    out = io.StringIO()
    with Progress(0, "sley", stream=out, delay=0) as bar:
        for done in range(1, 6):
            bar(done, 5)
    assert out.getvalue() == "" and bar.done == 5
