// A discrepancy report (`scopekin discrepancy`): the verdict and the named effects, the held-out
// RMS error per output and per region before and after, and each output measured against the
// model before and after, the held-out blocks shaded: where the error sits.
import { makeChart } from './chart.js';

const fmt = (v, digits = 3) => (v === null || v === undefined || Number.isNaN(v) ? 'n/a' : Number(Number(v).toPrecision(digits)).toString());

function cell(row, text, tag = 'td') {
  const c = document.createElement(tag);
  c.textContent = text;
  row.appendChild(c);
  return c;
}

function parameterText(p) {
  if (typeof p !== 'object' || p === null) return String(p);
  const sd = p.sd === null || p.sd === undefined ? (p.sd_unavailable ? ` (SD: ${p.sd_unavailable})` : '') : ` ± ${fmt(p.sd)}`;
  return `${p.name ?? ''} = ${fmt(p.value)}${p.unit ? ` ${p.unit}` : ''}${sd}`;
}

function effectsTable(table, report) {
  const head = table.insertRow();
  for (const h of ['effect', 'parameters', 'share of the held-out excess error explained', 'where it closes the gap']) cell(head, h, 'th');
  if (!report.effects || report.effects.length === 0) {
    cell(table.insertRow(), 'none named');
    return;
  }
  for (const e of report.effects) {
    const row = table.insertRow();
    cell(row, e.name);
    cell(row, (e.parameters || []).map(parameterText).join('; '));
    cell(row, `${Math.round(100 * (e.share_explained ?? 0))} %`);
    cell(row, (e.where?.regions_where_it_closes_the_gap || []).join(', ') || '–');
  }
}

function errorTable(table, report) {
  const head = table.insertRow();
  for (const h of ['output', 'held-out RMS before', 'after', 'reduction']) cell(head, h, 'th');
  for (const [output, before] of Object.entries(report.rmse_before || {})) {
    const after = report.rmse_after?.[output];
    const row = table.insertRow();
    cell(row, output);
    cell(row, fmt(before));
    cell(row, fmt(after));
    cell(row, before > 0 ? `${Math.round(100 * (1 - after / before))} %` : 'n/a');
  }
}

function regionTable(table, report) {
  const regions = Object.entries(report.rmse_by_region || {});
  if (regions.length === 0) return;
  const outputs = Object.keys(regions[0][1]);
  const head = table.insertRow();
  cell(head, 'region (held-out RMS before → after)', 'th');
  for (const o of outputs) cell(head, o, 'th');
  for (const [region, byOutput] of regions) {
    const row = table.insertRow();
    cell(row, region);
    for (const o of outputs) cell(row, byOutput[o] ? `${fmt(byOutput[o].before)} → ${fmt(byOutput[o].after)}` : '–');
  }
}

/// Shades the held-out samples' spans.
function heldOutPlugin(series) {
  return {
    hooks: {
      drawClear: [(u) => {
        const { ctx } = u;
        const { top, height } = u.bbox;
        ctx.save();
        ctx.fillStyle = 'rgba(255,255,255,0.07)';
        let start = null;
        const t = series.time_s;
        for (let k = 0; k <= t.length; k++) {
          const held = k < t.length && series.held_out[k] === 1;
          if (held && start === null) start = t[k];
          if (!held && start !== null) {
            const x0 = u.valToPos(start, 'x', true);
            const x1 = u.valToPos(t[Math.min(k, t.length - 1)], 'x', true);
            ctx.fillRect(x0, top, Math.max(x1 - x0, 1), height);
            start = null;
          }
        }
        ctx.restore();
      }],
    },
  };
}

function outputCharts(container, seriesByOutput) {
  const width = Math.max((container.clientWidth || 900) - 24, 300);
  const axis = { stroke: '#c8ccd0', size: 60, grid: { stroke: 'rgba(255,255,255,0.08)' } };
  for (const [key, s] of Object.entries(seriesByOutput)) {
    makeChart({
      title: `${key}: measured, the model before and after (held-out blocks shaded)`,
      width,
      height: 170,
      scales: { x: { time: false } },
      plugins: [heldOutPlugin(s)],
      series: [
        { label: 't [s]' },
        { label: 'measured', stroke: '#ffffff', width: 1 },
        { label: 'before', stroke: '#e69f00', width: 1.2 },
        { label: 'after', stroke: '#00bcd4', width: 1.2 },
      ],
      axes: [axis, axis],
    }, [s.time_s, s.measured, s.before, s.after], container);
  }
}

export function showDiscrepancy(data) {
  document.getElementById('run').hidden = true;
  document.getElementById('discrepancy').hidden = false;
  document.getElementById('title').textContent = data.title;
  document.getElementById('subtitle').textContent = data.subtitle;
  const r = data.report;
  const most = r.most_affected_output;
  document.getElementById('verdict').textContent = `verdict: ${r.verdict}` +
    (most ? ` · most affected output ${most.name}: held-out RMS ${fmt(most.held_out_rmse_before)} → ${fmt(most.held_out_rmse_after)} (${Math.round(100 * (most.reduction ?? 0))} % less)` : '');
  effectsTable(document.getElementById('effects'), r);
  errorTable(document.getElementById('errors'), r);
  regionTable(document.getElementById('regions'), r);
  outputCharts(document.getElementById('outputs'), data.series);
}
