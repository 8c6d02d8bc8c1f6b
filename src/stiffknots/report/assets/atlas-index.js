(function () {
  "use strict";
  var table = document.getElementById("knots");
  var tbody = table.tBodies[0];
  // every row: the first page in the table, the others waiting in a template (never laid
  // out until a page shows them: an index of thousands of knots opens as fast as a small one)
  var rows = Array.prototype.slice.call(tbody.rows);
  var more = document.getElementById("knots-more");
  if (more) rows = rows.concat(Array.prototype.slice.call(more.content.children));
  rows.forEach(function (r, k) { r.setAttribute("data-order", k); });
  var matched = rows.slice(), pageNo = 0;
  var pager = document.getElementById("pager");
  var sizeSel = document.getElementById("page-size");
  var pageInfo = document.getElementById("page-info");
  var prevBtn = document.getElementById("page-prev"), nextBtn = document.getElementById("page-next");
  var filterBox = document.getElementById("filter");
  var shapeSel = document.getElementById("shape-filter");
  var modelSel = document.getElementById("model");
  var countEl = document.getElementById("count");
  var heads = Array.prototype.slice.call(table.tHead.rows[0].cells);
  var sortCol = -1, sortDir = 1;

  function model() { return document.body.getAttribute("data-model"); }
  function key(td) {
    var v = td.getAttribute("data-v-" + model());
    if (v === null) v = td.getAttribute("data-v");
    return v === null || v === "" ? null : v;
  }
  function compare(a, b) {
    var type = heads[sortCol].getAttribute("data-type");
    var ka = key(a.cells[sortCol]), kb = key(b.cells[sortCol]);
    if (ka === null || kb === null) {  // missing values last, in both directions
      if (ka === kb) return a.getAttribute("data-order") - b.getAttribute("data-order");
      return ka === null ? 1 : -1;
    }
    var d = type === "num" ? parseFloat(ka) - parseFloat(kb) : ka.localeCompare(kb);
    if (d === 0) return a.getAttribute("data-order") - b.getAttribute("data-order");
    return sortDir * d;
  }
  function sortBy(col, dir) {
    sortCol = col; sortDir = dir;
    heads.forEach(function (th, k) {
      if (th.hasAttribute("aria-sort"))
        th.setAttribute("aria-sort", k === col ? (dir > 0 ? "ascending" : "descending") : "none");
    });
    rows.sort(compare);
    applyFilter();
  }
  function pageSize() {
    var v = sizeSel ? parseInt(sizeSel.value, 10) : 0;
    return v > 0 ? v : rows.length || 1;
  }
  function render() {
    var size = pageSize(), pages = Math.max(1, Math.ceil(matched.length / size));
    pageNo = Math.min(Math.max(pageNo, 0), pages - 1);
    var from = pageNo * size, shown = matched.slice(from, from + size);
    var frag = document.createDocumentFragment();
    shown.forEach(function (r) { r.hidden = false; frag.appendChild(r); });
    tbody.replaceChildren(frag);
    var text = matched.length + " of " + rows.length + " knots shown";
    if (pages > 1)
      text = matched.length + " of " + rows.length + " knots match; " + (from + 1) + "–" +
        (from + shown.length) + " shown";
    countEl.textContent = text;
    if (pager) {
      // a table that fits one page of the default size needs no pager
      pager.hidden = pages === 1 && rows.length <= parseInt(pager.getAttribute("data-rows"), 10);
      pageInfo.textContent = "page " + (pageNo + 1) + " of " + pages;
      prevBtn.disabled = pageNo === 0;
      nextBtn.disabled = pageNo >= pages - 1;
    }
  }
  if (pager) {
    prevBtn.addEventListener("click", function () { pageNo--; render(); });
    nextBtn.addEventListener("click", function () { pageNo++; render(); });
    sizeSel.addEventListener("change", function () { pageNo = 0; render(); });
  }
  heads.forEach(function (th, k) {
    var b = th.querySelector("button");
    if (!b) return;
    b.addEventListener("click", function () {
      sortBy(k, sortCol === k ? -sortDir : 1);
    });
  });
  function applyFilter(keepPage) {
    var q = filterBox.value.trim().toLowerCase();
    var s = shapeSel ? shapeSel.value : "";
    var m = model();
    matched = rows.filter(function (r) {
      var text = r.getAttribute("data-search-" + m) || r.getAttribute("data-search") || "";
      var shape = r.getAttribute("data-shape-" + m) || "";
      return (!q || text.indexOf(q) >= 0) && (!s || shape === s);
    });
    if (keepPage !== true) pageNo = 0;
    render();
  }
  filterBox.addEventListener("input", applyFilter);
  if (shapeSel) shapeSel.addEventListener("change", applyFilter);

  var plot = document.getElementById("eps-plot");
  var FIG = JSON.parse(document.getElementById("eps-data").textContent);
  var CONFIG = {displaylogo: false, responsive: true,
                modeBarButtonsToRemove: ["sendDataToCloud", "lasso2d", "select2d"]};
  function visibility() {
    return FIG.data.map(function (t) {
      return !(t.meta && t.meta.model) || t.meta.model === model();
    });
  }
  var drawn = false;
  function draw() {
    if (!window.Plotly || !plot) return;
    Plotly.newPlot(plot, FIG.data, FIG.layout, CONFIG).then(function () {
      drawn = true;
      Plotly.restyle(plot, {visible: visibility()});
    });
    plot.on("plotly_click", function (ev) {
      var p = ev.points && ev.points[0];
      if (p && p.customdata && p.customdata[5]) window.location.href = p.customdata[5];
    });
  }
  // plotly.js (3.5 MB) is loaded once the table is shown, so that the table is read and
  // sorted at once and the plot follows
  function loadPlotly() {
    if (window.Plotly) { draw(); return; }
    var js = document.createElement("script");
    js.src = "plotly.min.js";
    js.onload = draw;
    document.head.appendChild(js);
  }
  if (document.readyState === "complete") loadPlotly();
  else window.addEventListener("load", loadPlotly);
  if (modelSel) modelSel.addEventListener("change", function () {
    document.body.setAttribute("data-model", modelSel.value);
    if (sortCol >= 0) sortBy(sortCol, sortDir);
    else applyFilter(true);
    if (drawn) Plotly.restyle(plot, {visible: visibility()});
  });
  applyFilter();
})();
