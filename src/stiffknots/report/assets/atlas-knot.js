(function () {
  "use strict";
  var STATES = JSON.parse(document.getElementById("states-data").textContent);
  var COLORSCALE = JSON.parse(document.getElementById("colorscale-data").textContent);
  var ZONE_COLOURS = JSON.parse(document.getElementById("zone-colours-data").textContent);
  var colourSel = document.getElementById("colour-select");
  var legend = document.getElementById("zone-legend");
  var missing = document.getElementById("zone-missing");
  var current = 0;
  var div = document.getElementById("view3d");
  var sel = document.getElementById("state-select");
  var caption = document.getElementById("view-caption");
  var CONFIG = {displaylogo: false, responsive: true};

  function meshTrace(st) {
    // a closed tube gets a copy of its first ring at the end, coloured 1 instead of 0, so that
    // the cyclic colour does not run back through the whole scale on the last band
    var n = st.rings, s = st.sides, v = st.v;
    var m = st.closed ? n + 1 : n, N = m * s;
    var x = new Array(N), y = new Array(N), z = new Array(N), c = new Array(N);
    for (var p = 0; p < N; p++) {
      var q = p % (n * s), r = Math.floor(p / s);
      x[p] = v[3 * q]; y[p] = v[3 * q + 1]; z[p] = v[3 * q + 2];
      c[p] = r < n ? st.t[r] : 1.0;
    }
    // by contact structure: one flat colour a face (no blend through the other kinds'
    // colours), the larger code of the two beads of its bond, so a one-bead zone shows
    var byZone = colourSel && colourSel.value === "zones" && st.zones;
    var I = [], J = [], K = [], F = [];
    for (var k = 0; k < m - 1; k++) {
      var fc = byZone ? ZONE_COLOURS[Math.max(st.zones[k % n], st.zones[(k + 1) % n])] : null;
      for (var j = 0; j < s; j++) {
        var j1 = (j + 1) % s;
        var a = k * s + j, b = k * s + j1, cc = (k + 1) * s + j1, d = (k + 1) * s + j;
        I.push(a, a); J.push(cc, d); K.push(b, cc);
        if (byZone) F.push(fc, fc);
      }
    }
    if (!st.closed) {  // flat end caps as triangle fans
      [0, n - 1].forEach(function (r) {
        for (var j = 1; j < s - 1; j++) {
          I.push(r * s); J.push(r * s + j); K.push(r * s + j + 1);
          if (byZone) F.push(ZONE_COLOURS[st.zones[r]]);
        }
      });
    }
    var colour = byZone ? {facecolor: F}
      : {intensity: c, colorscale: COLORSCALE, cmin: 0, cmax: 1};
    return Object.assign({type: "mesh3d", x: x, y: y, z: z, i: I, j: J, k: K,
            showscale: false, hoverinfo: "skip",
            flatshading: false,
            lighting: {ambient: 0.5, diffuse: 0.7, specular: 0.15, roughness: 0.5,
                       fresnel: 0.1},
            // plotly's mesh3d lights the side facing away from lightposition: put the light
            // opposite the camera, so that the side seen first is lit
            lightposition: {x: -1e5 * st.eye.x, y: -1e5 * st.eye.y, z: -1e5 * st.eye.z}},
            colour);
  }
  function layout(st) {
    function axis(k) { return {visible: false, showspikes: false, range: st.range[k]}; }
    return {margin: {l: 0, r: 0, t: 0, b: 0}, paper_bgcolor: "#fff", showlegend: false,
            scene: {aspectmode: "manual", aspectratio: st.aspect,
                    xaxis: axis(0), yaxis: axis(1), zaxis: axis(2),
                    bgcolor: "#fff",
                    camera: {eye: st.eye, up: {x: 0, y: 0, z: 1}, center: {x: 0, y: 0, z: 0},
                             projection: {type: "orthographic"}}}};
  }
  function show(k) {
    var st = STATES[k];
    if (!st) return;
    current = k;
    // a new plot, not Plotly.react: react keeps a mesh's old colouring when it switches
    // between intensity and face colours
    Plotly.newPlot(div, [meshTrace(st)], layout(st), CONFIG);
    if (legend) {
      var on = !!(colourSel && colourSel.value === "zones");
      legend.hidden = !on;
      missing.hidden = !on || !!st.zones;
    }
    sel.value = String(k);
    caption.textContent = st.caption;
    Array.prototype.forEach.call(document.querySelectorAll("tr.state-row"), function (r) {
      r.classList.toggle("active", r.getAttribute("data-state") === String(k));
    });
  }
  if (sel) sel.addEventListener("change", function () { show(parseInt(sel.value, 10)); });
  if (colourSel) colourSel.addEventListener("change", function () { show(current); });
  Array.prototype.forEach.call(document.querySelectorAll("tr.state-row"), function (r) {
    r.addEventListener("click", function () {
      var k = r.getAttribute("data-state");
      if (k !== null && k !== "") { show(parseInt(k, 10)); div.scrollIntoView({block: "nearest"}); }
    });
  });
  if (window.Plotly && div && STATES.length) show(0);
})();
