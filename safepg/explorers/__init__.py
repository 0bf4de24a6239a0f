"""Interactive explorers: one HTML + JavaScript component with a Python twin.

- :mod:`~safepg.explorers.component`: the kernel-free component (sliders, selects, SVG plots),
  computed in the reader's browser, and its ipywidgets twin (:mod:`~safepg.explorers.kernel_view`);
- :mod:`~safepg.explorers.upsilon`: Upsilon_delta(N) and N* of Section 4.3 for any task.
"""
