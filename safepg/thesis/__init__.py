"""The reproduction of the thesis, built on the :mod:`safepg` method.

Everything that knows a number the thesis prints or a section it belongs to lives here:
the named experiments of Chapter 5 with their printed values, the reports, figures and
tables, the searches for the settings the text leaves unstated, the scorecard, the checks
of the printed lemmas and errata, and the book's interactive explorers. The method itself
(:mod:`safepg` outside this package) never imports it.
"""
