"""The book's interactive explorers: one HTML + JavaScript component with a Python twin.

- :mod:`~safepg.thesis.explorers.component`: the kernel-free component (sliders, selects,
  SVG plots) and its ipywidgets twin;
- :mod:`~safepg.thesis.explorers.curves`: the explorers of closed-form curves (the LQG's
  J(theta), Upsilon_delta(N));
- :mod:`~safepg.thesis.explorers.live_learner`: Algorithm 4.1 run live in the page.
"""
