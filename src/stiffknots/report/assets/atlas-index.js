(function () {
  "use strict";
  var table = document.getElementById("knots");
  var tbody = table.tBodies[0];
  var rows = Array.prototype.slice.call(tbody.rows);
  rows.forEach(function (r, k) { r.setAttribute("data-order", k); });
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
    rows.slice().sort(compare).forEach(function (r) { tbody.appendChild(r); });
  }
  heads.forEach(function (th, k) {
    var b = th.querySelector("button");
    if (!b) return;
    b.addEventListener("click", function () {
      sortBy(k, sortCol === k ? -sortDir : 1);
    });
  });
  function applyFilter() {
    var q = filterBox.value.trim().toLowerCase();
    var s = shapeSel ? shapeSel.value : "";
    var m = model(), shown = 0;
    rows.forEach(function (r) {
      var text = r.getAttribute("data-search-" + m) || r.getAttribute("data-search") || "";
      var shape = r.getAttribute("data-shape-" + m) || "";
      var ok = (!q || text.indexOf(q) >= 0) && (!s || shape === s);
      r.hidden = !ok;
      if (ok) shown++;
    });
    countEl.textContent = shown + " of " + rows.length + " knots shown";
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
  if (window.Plotly && plot) {
    Plotly.newPlot(plot, FIG.data, FIG.layout, CONFIG);
    plot.on("plotly_click", function (ev) {
      var p = ev.points && ev.points[0];
      if (p && p.customdata && p.customdata[5]) window.location.href = p.customdata[5];
    });
  }
  if (modelSel) modelSel.addEventListener("change", function () {
    document.body.setAttribute("data-model", modelSel.value);
    if (sortCol >= 0) sortBy(sortCol, sortDir);
    applyFilter();
    if (window.Plotly && plot) Plotly.restyle(plot, {visible: visibility()});
  });
  applyFilter();
})();
