// The root locus page (locus.html): the eigenvalues of `kanesim linearize --sweep` in the
// complex plane, coloured by the parameter, and their real parts against the parameter.
//
// Test hook window.kanesimLocus (docs/linearize.md, "The root locus as a page"): ready,
// failed, errors, and what the plots hold, read back from the dygraphs: locusPoints() the
// [re, im, colour bin] of every plotted point, realParts() the rows [value, re1, re2, ...].
(function () {
  'use strict';
  const hook = { ready: false, failed: false, errors: [] };
  window.kanesimLocus = hook;
  window.addEventListener('error', (e) => hook.errors.push('error: ' + e.message));
  window.addEventListener('unhandledrejection', (e) => hook.errors.push('unhandled: ' + e.reason));
  document.addEventListener('securitypolicyviolation',
    (e) => hook.errors.push('blocked by the page policy: ' + e.blockedURI + ' (' + e.violatedDirective + ')'));

  const kBins = 64;  // colours: at most this many series in the complex-plane plot

  // Blue (the first value) to red (the last).
  function colour(t) { return 'hsl(' + Math.round(240 * (1 - t)) + ', 85%, 45%)'; }

  function fail(message) {
    hook.failed = true;
    hook.errors.push(message);
    const m = document.getElementById('message');
    m.textContent = message;
    m.hidden = false;
  }

  function build() {
    const data = JSON.parse(document.getElementById('kanesim-locus').textContent);
    const name = data.parameter, values = data.values, ev = data.eigenvalues;
    const n = values.length, m = n > 0 ? ev[0].length : 0;
    document.getElementById('title').textContent = data.title;
    document.getElementById('note').textContent = n + ' value(s) of ' + name + ', ' + m +
      ' eigenvalue(s) each, sorted by modulus (the CSV table\'s order).';
    if (n === 0) { fail('no values in the sweep'); return; }
    const nb = Math.min(n, kBins);
    const binOf = (i) => (n === 1 ? 0 : Math.min(nb - 1, Math.floor(i * nb / n)));
    const binRange = [];
    for (let b = 0; b < nb; ++b) binRange.push([Infinity, -Infinity]);
    for (let i = 0; i < n; ++i) {
      const r = binRange[binOf(i)];
      r[0] = Math.min(r[0], values[i]);
      r[1] = Math.max(r[1], values[i]);
    }
    const lo = values[0], hi = values[n - 1];
    const tOf = (v) => (hi > lo ? (v - lo) / (hi - lo) : 0);
    const labels = ['real part'], colours = [];
    for (let b = 0; b < nb; ++b) {
      const [a, z] = binRange[b];
      labels.push(a === z ? name + ' = ' + a : name + ' = ' + a + ' … ' + z);
      colours.push(colour(tOf((a + z) / 2)));
    }
    // One row per eigenvalue: x = real part, the imaginary part in its bin's column.
    const rows = [];
    for (let i = 0; i < n; ++i) {
      for (let k = 0; k < m; ++k) {
        const re = ev[i][k][0], im = ev[i][k][1];
        if (re === null || im === null) continue;  // a non-finite number
        const row = new Array(nb + 1).fill(null);
        row[0] = re;
        row[binOf(i) + 1] = im;
        rows.push(row);
      }
    }
    rows.sort((a, b) => a[0] - b[0]);
    document.getElementById('scale-lo').textContent = name + ' = ' + lo;
    document.getElementById('scale-hi').textContent = String(hi);
    const stops = [];
    for (let s = 0; s <= 8; ++s) stops.push(colour(s / 8));
    document.getElementById('bar').style.background = 'linear-gradient(to right, ' + stops.join(', ') + ')';
    const locus = new Dygraph(document.getElementById('locus'), rows, {
      labels: labels, colors: colours, drawPoints: true, strokeWidth: 0, pointSize: 2.5,
      highlightCircleSize: 4, legend: 'onmouseover', labelsSeparateLines: true,
      xlabel: 'real part [1/s]', ylabel: 'imaginary part [rad/s]', drawAxesAtZero: true,
      xRangePad: 12, yRangePad: 12,
    });
    // Real parts against the parameter: one series per eigenvalue index, drawn as points
    // only (the index follows the sort by modulus, which swaps a pair ±σ between values:
    // lines would zigzag between branches).
    const rrows = [];
    for (let i = 0; i < n; ++i) {
      const row = [values[i]];
      for (let k = 0; k < m; ++k) row.push(ev[i][k][0]);
      rrows.push(row);
    }
    const rlabels = [name];
    for (let k = 0; k < m; ++k) rlabels.push('Re λ' + (k + 1));
    const real = new Dygraph(document.getElementById('real'), rrows, {
      labels: rlabels, drawPoints: true, strokeWidth: 0, pointSize: 2.5, legend: 'onmouseover',
      labelsSeparateLines: true, xlabel: name, ylabel: 'real part [1/s]', drawAxesAtZero: true, yRangePad: 12,
    });
    hook.locusPoints = () => {
      const out = [];
      for (let r = 0; r < locus.numRows(); ++r)
        for (let c = 1; c < locus.numColumns(); ++c) {
          const y = locus.getValue(r, c);
          if (y !== null) out.push([locus.getValue(r, 0), y, c - 1]);
        }
      return out;
    };
    hook.realParts = () => {
      const out = [];
      for (let r = 0; r < real.numRows(); ++r) {
        const row = [];
        for (let c = 0; c < real.numColumns(); ++c) row.push(real.getValue(r, c));
        out.push(row);
      }
      return out;
    };
    hook.binColours = colours;
    hook.ready = true;
  }

  try {
    if (typeof Dygraph === 'undefined') fail('dygraphs did not load');
    else build();
  } catch (e) {
    fail('the page failed: ' + e);
  }
})();
