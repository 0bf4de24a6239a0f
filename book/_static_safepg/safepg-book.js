// safepg book: mark every box of the text column that scrolls sideways (a wide table, a long
// formula, a long printed line) with the class safepg-scrollable and add a visible
// "scroll sideways" cue below it; the cue goes away when the box fits. Reruns after MathJax
// has typeset the page and whenever the window is resized. Also gives the theme's and
// myst-nb's controls accessible names that contain their visible words (nameControls).
(function () {
  "use strict";
  const HINT = "safepg-scroll-hint";
  const hints = new WeakMap();  // scrolling box -> its cue element

  function scrollsSideways(el) {
    const o = getComputedStyle(el).overflowX;
    return (o === "auto" || o === "scroll") && el.scrollWidth > el.clientWidth + 1 && el.clientWidth > 0;
  }

  function atEnd(el) {
    el.classList.toggle("safepg-at-end", el.scrollLeft + el.clientWidth >= el.scrollWidth - 1);
  }

  function mark() {
    const article = document.querySelector("article.bd-article") || document.querySelector("main");
    if (!article) return;
    // An inline formula wider than the column (its typeset box wider than the span the theme
    // caps at the column's width) gets a box of its own that can scroll.
    for (const m of article.querySelectorAll("span.math")) {
      const c = m.querySelector("mjx-container");
      if (c && !m.classList.contains("safepg-wide-math") && c.getBoundingClientRect().width > m.clientWidth + 2)
        m.classList.add("safepg-wide-math");
    }
    for (const el of article.querySelectorAll("*")) {
      if (el.classList.contains(HINT)) continue;
      const scrolls = scrollsSideways(el);
      const had = el.classList.contains("safepg-scrollable");
      if (scrolls && !had) {
        el.classList.add("safepg-scrollable");
        const hint = document.createElement("div");
        hint.className = HINT;
        hint.setAttribute("aria-hidden", "true");
        hint.textContent = "scroll sideways to see all of it";
        // A formula's box sits in Sphinx's div.math (a flex row): the cue goes below that.
        const anchor = el.tagName === "MJX-CONTAINER" && el.parentElement.classList.contains("math")
          ? el.parentElement : el;
        anchor.insertAdjacentElement("afterend", hint);
        hints.set(el, hint);
        el.addEventListener("scroll", () => atEnd(el), {passive: true});
      } else if (!scrolls && had) {
        el.classList.remove("safepg-scrollable", "safepg-at-end");
        if (hints.has(el)) hints.get(el).remove();
        hints.delete(el);
      }
      if (scrolls) atEnd(el);
    }
  }

  function liftCaptions() {
    // A table's caption is part of the table, so in a table that scrolls sideways the
    // caption scrolls away with it and is cut off: show it above the scrolling box instead.
    for (const cap of document.querySelectorAll(".pst-scrollable-table-container > table > caption")) {
      const box = cap.closest(".pst-scrollable-table-container");
      const div = document.createElement("div");
      div.className = "safepg-caption " + cap.className;
      while (cap.firstChild) div.appendChild(cap.firstChild);
      cap.remove();
      box.parentElement.insertBefore(div, box);
    }
  }

  function nameControls() {
    // Accessible names that contain the visible label (WCAG 2.5.3, axe's
    // label-content-name-mismatch), so a speech-input user can say what they see.
    // myst-nb names every "Show code cell source" toggle "Toggle hidden content": drop that
    // name and let the visible words name it.
    for (const s of document.querySelectorAll("details.hide > summary[aria-label]")) s.removeAttribute("aria-label");
    // The theme's search field shows "Search Ctrl+K" but is named "Search": name it by its
    // words, and tell assistive technology about the shortcut.
    for (const b of document.querySelectorAll("button.search-button__button[aria-label]")) {
      if (!b.querySelector(".search-button__kbd-shortcut")) continue;
      b.removeAttribute("aria-label");
      b.setAttribute("aria-keyshortcuts", "Control+K");
    }
    // The theme's colour-mode button ("Color mode") holds icons titled Light / Dark / System
    // Settings (Font Awesome turns the title into the SVG's name): icons are decoration here.
    for (const i of document.querySelectorAll(".theme-switch-button .theme-switch")) {
      i.removeAttribute("title");
      if (i.tagName.toLowerCase() === "svg") {
        i.querySelectorAll("title").forEach(t => t.remove());
        i.removeAttribute("aria-labelledby");
        i.removeAttribute("role");
        i.setAttribute("aria-hidden", "true");
      }
    }
  }

  let timer = null;
  function later() { clearTimeout(timer); timer = setTimeout(mark, 150); }
  document.addEventListener("DOMContentLoaded", nameControls);
  window.addEventListener("load", () => {
    nameControls();  // again: Font Awesome replaces its <i> icons by SVGs after DOMContentLoaded
    liftCaptions();
    // Once the cues stand as a reader will see them (after MathJax when the page has maths), say so
    // on <html>: a test of the cues waits for that, not for a guessed delay.
    const marked = () => { mark(); document.documentElement.dataset.safepgCues = "marked"; };
    if (window.MathJax && MathJax.startup && MathJax.startup.promise) { mark(); MathJax.startup.promise.then(marked); }
    else marked();
  });
  window.addEventListener("resize", later);
  document.addEventListener("DOMContentLoaded", later);
})();
