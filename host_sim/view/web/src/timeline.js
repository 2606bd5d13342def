// The timeline under the scene: the handle's force and torque, the tip along the colon (the box's
// estimate with its one-SD band beside the truth and the insertion), the largest contact force,
// with the box's alarms as bands, the truth's episodes and the fault flags as strips, and the
// time cursor. A click or a drag on any chart moves the cursor.
import { makeChart } from './chart.js';

export const kAlarmStyle = {
  self_lock: { label: 'loop / self-lock', fill: 'rgba(0,114,178,0.22)', solid: '#0072b2' },
  contact_force_warning: { label: 'contact force warning', fill: 'rgba(240,228,66,0.35)', solid: '#c9b800' },
  contact_force_critical: { label: 'contact force critical', fill: 'rgba(213,94,0,0.30)', solid: '#d55e00' },
};

function bandsPlugin(view) {
  return {
    hooks: {
      drawClear: [
        (u) => {
          const { ctx } = u;
          const { top, height } = u.bbox;
          ctx.save();
          for (const a of view.data.alarms) {
            const x0 = u.valToPos(a.start_s, 'x', true);
            const x1 = u.valToPos(a.end_s ?? view.duration_s, 'x', true);
            ctx.fillStyle = kAlarmStyle[a.kind]?.fill ?? 'rgba(128,128,128,0.2)';
            ctx.fillRect(x0, top, Math.max(x1 - x0, 1), height);
          }
          ctx.restore();
        },
      ],
      draw: [
        (u) => {
          const { ctx } = u;
          const { top, height } = u.bbox;
          ctx.save();
          // The truth's loop episodes and the fault flags: strips along the top edge.
          ctx.fillStyle = '#0072b2';
          for (const e of view.data.truth_episodes.loop) {
            const x0 = u.valToPos(e.onset_s, 'x', true);
            const x1 = u.valToPos(e.end_s ?? view.duration_s, 'x', true);
            ctx.fillRect(x0, top, Math.max(x1 - x0, 2), 4 * devicePixelRatio);
          }
          ctx.fillStyle = '#d55e00';
          for (const e of view.data.truth_episodes.critical_14N) {
            const x0 = u.valToPos(e.onset_s, 'x', true);
            const x1 = u.valToPos(e.end_s ?? view.duration_s, 'x', true);
            ctx.fillRect(x0, top + 5 * devicePixelRatio, Math.max(x1 - x0, 2), 4 * devicePixelRatio);
          }
          ctx.fillStyle = '#888888';
          for (const f of view.data.faults) {
            const x0 = u.valToPos(f.start_s, 'x', true);
            const x1 = u.valToPos(f.end_s ?? view.duration_s, 'x', true);
            ctx.fillRect(x0, top + height - 4 * devicePixelRatio, Math.max(x1 - x0, 2), 4 * devicePixelRatio);
          }
          ctx.restore();
        },
      ],
      ready: [
        (u) => {
          // The time cursor: a line over the chart, moved without redrawing the chart.
          const line = document.createElement('div');
          line.className = 'time-cursor';
          u.over.appendChild(line);
          const scrub = (e) => {
            const rect = u.over.getBoundingClientRect();
            view.setTime(u.posToVal(e.clientX - rect.left, 'x'));
          };
          let dragging = false;
          u.over.addEventListener('mousedown', (e) => { dragging = true; scrub(e); });
          u.over.addEventListener('mousemove', (e) => { if (dragging) scrub(e); });
          window.addEventListener('mouseup', () => { dragging = false; });
        },
      ],
    },
  };
}

function axisStyle(extra) {
  return { stroke: '#c8ccd0', size: 60, grid: { stroke: 'rgba(255,255,255,0.08)' }, ticks: { stroke: 'rgba(255,255,255,0.2)' }, ...extra };
}

/// An empty right-hand axis, so that every chart's time axis spans the same pixels.
const rightSpacer = () => axisStyle({ side: 1, label: ' ', values: () => [], grid: { show: false }, ticks: { show: false } });

export class Timeline {
  constructor(container, view) {
    this.view = view;
    this.charts = [];
    const width = Math.max((container.clientWidth || 900) - 24, 300);
    const common = (title, height) => ({
      title,
      width,
      height,
      cursor: { sync: { key: 'scopekin' }, drag: { x: false, y: false } },
      legend: { live: true },
      plugins: [bandsPlugin(view)],
      scales: { x: { time: false } },
    });
    const columns = this.columns();

    this.charts.push(makeChart({
      ...common('Handle: what the box measures', 150),
      series: [
        { label: 't [s]' },
        { label: 'force [N]', stroke: '#e69f00', width: 1.5, scale: 'N' },
        { label: 'torque [N·mm]', stroke: '#56b4e9', width: 1, scale: 'Nmm' },
      ],
      axes: [axisStyle({}), axisStyle({ scale: 'N', label: 'N' }), axisStyle({ scale: 'Nmm', side: 1, label: 'N·mm', grid: { show: false } })],
    }, columns[0], container));

    this.charts.push(makeChart({
      ...common(view.data.box_only ? 'Tip along the colon: the box (±1 SD) and the insertion' : 'Tip along the colon: the box (±1 SD) and the truth', 170),
      series: [
        { label: 't [s]' },
        { label: 'insertion [mm]', stroke: '#999999', width: 1, dash: [4, 4] },
        { label: 'true tip [mm]', stroke: '#ffffff', width: 1.5 },
        { label: 'box tip [mm]', stroke: '#00bcd4', width: 1.5 },
        { label: '−1 SD', stroke: 'rgba(0,188,212,0.3)', width: 0.5 },
        { label: '+1 SD', stroke: 'rgba(0,188,212,0.3)', width: 0.5 },
      ],
      bands: [{ series: [5, 4], fill: 'rgba(0,188,212,0.15)' }],
      axes: [axisStyle({}), axisStyle({ label: 'mm' }), rightSpacer()],
    }, columns[1], container));

    this.charts.push(makeChart({
      ...common(view.data.box_only ? 'Largest contact force: the box' : 'Largest contact force: the box and the truth', 150),
      series: [
        { label: 't [s]' },
        { label: 'true [N]', stroke: '#ffffff', width: 1.2 },
        { label: 'box [N]', stroke: '#00bcd4', width: 1.5 },
      ],
      axes: [axisStyle({ label: 't [s]' }), axisStyle({ label: 'N' }), rightSpacer()],
    }, columns[2], container));
  }

  /// Each chart's data from the view's series (null where a period lacks a value).
  columns() {
    const s = this.view.data.series;
    const nulls = (a) => a.map((v) => (v === undefined ? null : v));
    const minus = s.box_tip_path_mm.map((v, k) => (v === null || s.box_tip_sd_mm[k] === null ? null : v - s.box_tip_sd_mm[k]));
    const plus = s.box_tip_path_mm.map((v, k) => (v === null || s.box_tip_sd_mm[k] === null ? null : v + s.box_tip_sd_mm[k]));
    return [
      [s.time_s, nulls(s.handle_force_N), nulls(s.handle_torque_Nmm)],
      [s.time_s, nulls(s.insertion_mm), nulls(s.true_tip_path_mm), nulls(s.box_tip_path_mm), minus, plus],
      [s.time_s, nulls(s.true_max_force_N), nulls(s.box_max_force_N)],
    ];
  }

  /// New data (a live run's rows): every chart redrawn over the whole run so far.
  refresh() {
    const columns = this.columns();
    this.charts.forEach((c, k) => c.setData(columns[k]));
    this.moveCursor();
  }

  /// Moves the time cursor of every chart to the view's time.
  moveCursor() {
    for (const c of this.charts) {
      const line = c.over.querySelector('.time-cursor');
      if (line) line.style.left = `${c.valToPos(this.view.time_s, 'x')}px`;
    }
  }

  resize(width) {
    for (const c of this.charts) c.setSize({ width: Math.max(width - 24, 300), height: c.height });
    this.moveCursor();
  }
}
