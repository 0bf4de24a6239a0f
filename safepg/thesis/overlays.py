"""Our runs drawn over the authors' raw outputs (``safepg.thesis.authors``): one function per figure.

Each function draws our curve (mean and 95% band over seeds) over the authors' own run(s)
of the same setting, from the stored records and the data files, and returns the figure.
"""

from __future__ import annotations

# ---------------------------------------------------------------- Section 5.1: 1-D fixed-step runs


# ---------------------------------------------------------------- Section 5.2: 2-D runs


# ---------------------------------------------------------------- Section 5.3: cart-pole runs
