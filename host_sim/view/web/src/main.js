// The page of `scopekin view`: a run's colon and scope in 3D above its timeline, the box's
// estimate beside the truth, played, scrubbed and stepped alarm by alarm (host_sim/view/README.md).
import 'uplot/dist/uPlot.min.css';
import './view.css';
import { readEmbeddedData, indexAtOrBefore, alarmsAt, nextAlarmAfter } from './run_data.js';
import { RunScene } from './scene.js';
import { Timeline, kAlarmStyle } from './timeline.js';
import { connectLive } from './live.js';
import { caseInAddress, showEvaluation } from './evaluation.js';
import { showDiscrepancy } from './discrepancy.js';

const kSpeeds = [0.25, 0.5, 1, 2, 5, 10];
const kLiveChartPeriod_ms = 250;

class View {
  constructor(data) {
    this.data = data;
    const t = data.series.time_s;
    this.start_s = t.length ? t[0] : 0;
    this.duration_s = t.length ? t[t.length - 1] : 0;
    this.time_s = this.start_s;
    this.playing = false;
    this.speed = 1;
    this.live = data.kind === 'live';
    this.messagesReceived = 0;
    this.frameTimes = data.frames.map((f) => f.time_s);
    document.getElementById('title').textContent = data.title;
    document.getElementById('subtitle').textContent = data.subtitle;
    this.scene = new RunScene(document.getElementById('scene'), data);
    // A live page draws its charts once it has data (uPlot's axes need a range).
    this.timeline = this.live ? null : new Timeline(document.getElementById('timeline'), this);
    this.buildControls();
    this.buildAlarmList();
    window.addEventListener('resize', () => this.resize());
    this.setTime(this.start_s);
    let last = performance.now();
    const loop = (now) => {
      const dt = (now - last) / 1000;
      last = now;
      if (this.playing) {
        const next = this.time_s + dt * this.speed;
        if (next >= this.duration_s) this.playing = false;
        this.setTime(Math.min(next, this.duration_s));
        this.updatePlayButton();
      }
      this.drawCharts(now);
      // The scene is drawn when something in it changed (a new time, the camera moved, a resize).
      if (this.sceneDirty || this.scene.cameraMoved) {
        this.scene.render();
        this.sceneDirty = false;
        this.scene.cameraMoved = false;
        this.framesDrawn += 1;
      }
      requestAnimationFrame(loop);
    };
    this.framesDrawn = 0;
    requestAnimationFrame(loop);
    if (data.box_only)
      document.querySelector('.legend3d').innerHTML = '<div><span class="swatch" style="background:#00bcd4"></span>the box\'s tip along its model\'s colon, its 1-SD sphere</div>' +
        '<div><span class="swatch" style="background:#2ca02c"></span>its stations, coloured by their estimated force: &lt; 5, 5–10 (yellow), 10–14 (orange), ≥ 14 N (red)</div>' +
        '<div>only what the box knows: no truth, no scope shape</div>';
    if (this.live) {
      document.getElementById('banner').textContent = data.box_only ? 'live: the box\'s outputs as it computes them' : 'live: the run is streamed as it is simulated';
      connectLive(this);
    }
  }

  /// New live data: the cursor follows the run's end unless it was moved back.
  liveUpdate(openedAlarms, ended, replay) {
    const s = this.data.series;
    const following = this.time_s >= this.duration_s - 0.5;
    if (s.time_s.length) {
      this.start_s = s.time_s[0];
      this.duration_s = s.time_s[s.time_s.length - 1];
    }
    const scrub = document.getElementById('scrub');
    scrub.min = String(this.start_s);
    scrub.max = String(this.duration_s);
    for (const a of openedAlarms) this.addAlarmItem(a, this.data.alarms.indexOf(a));
    this.alarmItems.forEach((li, k) => this.labelAlarmItem(li, this.data.alarms[k]));
    this.chartData = 'stale';
    this.setTime(following ? this.duration_s : this.time_s);
    if (ended)
      document.getElementById('banner').innerHTML = replay
        ? 'The run is complete: <a href="">reload</a> for its replay (every period\'s alarms, the whole run).'
        : 'The live stream has ended.';
  }

  buildControls() {
    const play = document.getElementById('play');
    play.addEventListener('click', () => {
      if (this.time_s >= this.duration_s) this.setTime(this.start_s);
      this.playing = !this.playing;
      this.updatePlayButton();
    });
    const speed = document.getElementById('speed');
    for (const s of kSpeeds) {
      const o = document.createElement('option');
      o.value = String(s);
      o.textContent = `${s}×`;
      if (s === 1) o.selected = true;
      speed.appendChild(o);
    }
    speed.addEventListener('change', () => { this.speed = Number(speed.value); });
    const scrub = document.getElementById('scrub');
    scrub.min = String(this.start_s);
    scrub.max = String(this.duration_s);
    scrub.step = '0.005';
    scrub.addEventListener('input', () => this.setTime(Number(scrub.value)));
    document.getElementById('next-alarm').addEventListener('click', () => this.jumpToNextAlarm());
    window.addEventListener('keydown', (e) => {
      if (e.key === ' ') { e.preventDefault(); play.click(); }
      if (e.key === 'n') this.jumpToNextAlarm();
    });
  }

  updatePlayButton() {
    document.getElementById('play').textContent = this.playing ? '❚❚ pause' : '▶ play';
  }

  buildAlarmList() {
    this.alarmItems = [];
    this.data.alarms.forEach((a, k) => this.addAlarmItem(a, k));
  }

  addAlarmItem(a, k) {
    const li = document.createElement('li');
    li.dataset.index = String(k);
    this.labelAlarmItem(li, a);
    li.addEventListener('click', () => this.setTime(a.start_s));
    document.getElementById('alarms').appendChild(li);
    this.alarmItems.push(li);
    document.getElementById('alarm-count').textContent = String(this.data.alarms.length);
  }

  labelAlarmItem(li, a) {
    const style = kAlarmStyle[a.kind];
    const end = a.end_s === null ? (this.live ? 'now' : 'end') : `${a.end_s.toFixed(2)} s`;
    li.innerHTML = `<span class="swatch" style="background:${style?.solid ?? '#888'}"></span>` +
      `${a.start_s.toFixed(2)} s – ${end}: ${style?.label ?? a.kind}`;
  }

  jumpToNextAlarm() {
    const a = nextAlarmAfter(this.data.alarms, this.time_s);
    if (a) this.setTime(a.start_s);
  }

  /// Moves the cursor: the scene's frame, the box's estimate, the alarms up, the timeline.
  setTime(t) {
    this.time_s = Math.min(Math.max(t, this.start_s), this.duration_s);
    const s = this.data.series;
    const row = indexAtOrBefore(s.time_s, this.time_s);
    const frame = indexAtOrBefore(this.frameTimes, this.time_s);
    const stations = (s.station_path_mm[row] || []).map((p, k) => ({ path_mm: p, normal_N: s.station_normal_N[row][k] }));
    this.scene.show(frame, {
      true_tip_path_mm: s.true_tip_path_mm[row] ?? NaN,
      box_tip_path_mm: s.box_tip_path_mm[row] ?? NaN,
      box_tip_sd_mm: s.box_tip_sd_mm[row] ?? NaN,
      stations,
    });
    const up = new Set(alarmsAt(this.data.alarms, this.time_s).map((a) => this.data.alarms.indexOf(a)));
    this.alarmItems.forEach((li, k) => li.classList.toggle('active', up.has(k)));
    document.getElementById('time').textContent = `${this.time_s.toFixed(2)} s`;
    document.getElementById('frame-time').textContent = this.data.frames.length
      ? `shape at ${this.frameTimes[frame].toFixed(2)} s${this.data.frames[frame].label ? ` (${this.data.frames[frame].label})` : ''}`
      : 'no shapes recorded';
    const readout = document.getElementById('readout');
    const f = (v, d = 1) => (v === null || v === undefined ? '–' : v.toFixed(d));
    const truth = (text) => (this.data.box_only ? '' : text);
    readout.textContent = `handle ${f(s.handle_force_N[row])} N · insertion ${f(s.insertion_mm[row], 0)} mm · ` +
      `tip: box ${f(s.box_tip_path_mm[row], 0)} ± ${f(s.box_tip_sd_mm[row], 0)} mm${truth(`, true ${f(s.true_tip_path_mm[row], 0)} mm`)} · ` +
      `largest force: box ${f(s.box_max_force_N[row])} N${truth(`, true ${f(s.true_max_force_N[row])} N`)}`;
    document.getElementById('scrub').value = String(this.time_s);
    this.sceneDirty = true;
    if (this.chartData !== 'stale') this.chartData = 'cursor';
  }

  /// The charts, from the animation loop: the cursor at every drawn frame; a live run's new data
  /// at most every kLiveChartPeriod_ms (uPlot redraws the whole run each time).
  drawCharts(now) {
    if (this.chartData === 'stale') {
      if (now - (this.lastChartData ?? -1e9) < kLiveChartPeriod_ms) return;
      this.lastChartData = now;
      if (this.timeline) this.timeline.refresh();
      else if (this.data.series.time_s.length >= 2) {
        this.timeline = new Timeline(document.getElementById('timeline'), this);
        this.timeline.moveCursor();
      }
    } else if (this.chartData === 'cursor' && this.timeline) {
      this.timeline.moveCursor();
    }
    this.chartData = 'drawn';
  }

  resize() {
    this.scene.resize(document.getElementById('scene'));
    this.sceneDirty = true;
    if (this.timeline) this.timeline.resize(document.getElementById('timeline').clientWidth);
  }

  /// What the browser test reads (host_sim/view/web/test/view_test.mjs).
  state() {
    return {
      kind: this.data.kind,
      time_s: this.time_s,
      frame_index: this.scene.frameIndex,
      frames: this.data.frames.length,
      frames_drawn: this.framesDrawn,
      live: this.live,
      messages: this.messagesReceived,
      active_alarms: [...document.querySelectorAll('#alarms li.active')].map((li) => Number(li.dataset.index)),
      alarms: this.data.alarms,
    };
  }
}

function start() {
  try {
    const data = readEmbeddedData(document);
    if (data.kind === 'discrepancy') {
      showDiscrepancy(data);
      window.scopekinView = { state: () => ({ kind: 'discrepancy', verdict: data.report.verdict, charts: document.querySelectorAll('#outputs .uplot').length }) };
      return;
    }
    if (data.kind === 'evaluation') {
      // One page for the scorecard and every case: the address (#case=NAME) says which.
      window.addEventListener('hashchange', () => location.reload());
      const name = caseInAddress(data);
      if (name === undefined) {
        showEvaluation(data);
        window.scopekinView = { state: () => ({ kind: 'evaluation', cases: data.scorecard.cases.length, viewable: Object.keys(data.case_views).length }) };
        return;
      }
      window.scopekinView = new View(data.case_views[name]);
      document.getElementById('banner').innerHTML = `<a href="#">← the scorecard of ${data.title}</a> · case ${name} (its timeline at ${data.case_views[name].series.time_s.length} points; <code>scopekin view</code> on the case's folder shows every period)`;
      return;
    }
    window.scopekinView = new View(data);
  } catch (e) {
    document.getElementById('error').textContent = `This view cannot be shown: ${e.message}`;
    throw e;
  }
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
else start();
