(function () {
  "use strict";
  // the branch diagram of a knot page: ε against w/L, one curve per state, ε* at w = 0
  var div = document.getElementById("branch-plot");
  var data = document.getElementById("branch-data");
  if (!div || !data || typeof Plotly === "undefined") return;
  var FIG = JSON.parse(data.textContent);
  Plotly.newPlot(div, FIG.data, FIG.layout, {displaylogo: false, responsive: true});
})();
