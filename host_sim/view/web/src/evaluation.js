// An evaluation (`scopekin evaluate`): the scorecard's overall table (every estimator beside the
// baselines) and the cases, each a link to its replay (#case=NAME: the same page shows that case).

const fmt = (v, digits = 3) => (v === null || v === undefined || Number.isNaN(v) ? 'n/a' : Number(v.toPrecision(digits)).toString());
const spread = (d) => (d && d.cases ? `${fmt(d.median)} / ${fmt(d.p90)} / ${fmt(d.worst)}` : 'n/a');
const pct = (x) => `${Math.round(100 * x)} %`;

function detection(a) {
  if (!a || !a.episodes) return 'n/a';
  return `${a.detected} of ${a.episodes} (${pct(a.detected / a.episodes)}; ${a.late} late, ${a.missed} missed)`;
}

/// The overall table's rows: [measure, (estimator) => text].
const kMeasures = [
  ['tip position error, RMS [mm]', (e) => spread(e.tip_error_rms_mm)],
  ['tip position error, max [mm]', (e) => spread(e.tip_error_max_mm)],
  ['tip within its stated SD, 1 / 2 SD (pooled periods)', (e) => (e.tip_within_sd ? `${pct(e.tip_within_sd.within_1_sd_share)} / ${pct(e.tip_within_sd.within_2_sd_share)}` : 'n/a')],
  ['largest contact force error, RMS [N]', (e) => spread(e.force_error_rms_N)],
];
for (const [key, name] of [['loop_alarm', 'loop alarm'], ['warning_alarm', 'contact force ≥ 10 N'], ['critical_alarm', 'contact force ≥ 14 N']]) {
  kMeasures.push(
    [`${name}: episodes detected within 0.5 s`, (e) => detection(e[key])],
    [`${name}: median latency, detected and late [s]`, (e) => fmt(e[key]?.median_latency_s)],
    [`${name}: false alarms per 10 min (count)`, (e) => (e[key] ? `${fmt(e[key].false_alarms_per_10min)} (${e[key].false_alarms})` : 'n/a')],
    [`${name}: up after the episode ends [s]`, (e) => spread(e[key]?.linger_s)],
  );
}

function cell(row, text, tag = 'td') {
  const c = document.createElement(tag);
  c.textContent = text;
  row.appendChild(c);
  return c;
}

function overallTable(table, overall) {
  const head = table.insertRow();
  cell(head, 'measure', 'th');
  for (const e of overall.estimators) cell(head, e.name.replaceAll('_', ' '), 'th').title = e.label;
  for (const [measure, value] of kMeasures) {
    const row = table.insertRow();
    cell(row, measure);
    for (const e of overall.estimators) cell(row, value(e));
  }
}

function casesTable(table, data) {
  const head = table.insertRow();
  for (const h of ['case', 'style', 'status', 'simulated [s]', 'box tip RMS [mm]', 'box force RMS [N]', 'loop episodes detected', 'loop false alarms', '≥ 14 N detected', 'cecum'])
    cell(head, h, 'th');
  for (const c of data.scorecard.cases) {
    const box = c.estimators?.box;
    const row = table.insertRow();
    const name = cell(row, '');
    if (data.case_views[c.case]) {
      const link = document.createElement('a');
      link.href = `#case=${encodeURIComponent(c.case)}`;
      link.textContent = c.case;
      name.appendChild(link);
      row.classList.add('viewable');
      row.addEventListener('click', () => { location.hash = `case=${encodeURIComponent(c.case)}`; });
    } else {
      name.textContent = c.case;
      name.title = data.case_errors[c.case] ?? 'no replay';
    }
    cell(row, c.style || '');
    cell(row, c.status + (c.message ? `: ${c.message}` : ''));
    cell(row, fmt(c.duration_s, 4));
    cell(row, fmt(box?.tip_error_mm?.rms));
    cell(row, fmt(box?.force_error_N?.rms));
    cell(row, box?.loop_alarm?.episodes ? `${box.loop_alarm.detected} of ${box.loop_alarm.episodes}` : '–');
    cell(row, box?.loop_alarm ? String(box.loop_alarm.false_alarms) : '–');
    cell(row, box?.critical_alarm?.episodes ? `${box.critical_alarm.detected} of ${box.critical_alarm.episodes}` : '–');
    cell(row, c.procedure?.kind === 'physician' ? (c.procedure.cecum_reached ? `yes, ${fmt(c.procedure.insertion_at_cecum_mm, 4)} mm` : 'no') : '–');
  }
}

/// The case named in the address (#case=NAME), if the evaluation holds its replay.
export function caseInAddress(data) {
  const m = location.hash.match(/^#case=(.*)$/);
  if (!m) return undefined;
  const name = decodeURIComponent(m[1]);
  return data.case_views[name] ? name : undefined;
}

export function showEvaluation(data) {
  document.getElementById('run').hidden = true;
  document.getElementById('evaluation').hidden = false;
  document.getElementById('title').textContent = data.title;
  document.getElementById('subtitle').textContent = data.subtitle;
  overallTable(document.getElementById('overall'), data.scorecard.overall);
  casesTable(document.getElementById('cases'), data);
}
