// The run's data as `scopekin view` embeds it (schema "scopekin-view/1", host_sim/view/README.md),
// and the lookups the page needs: the frame at a time, a point at an arc along a centerline.

export function readEmbeddedData(doc) {
  const node = doc.getElementById('scopekin-data');
  if (!node) throw new Error('the page carries no run data (no #scopekin-data element)');
  const data = JSON.parse(node.textContent);
  if (data.schema !== 'scopekin-view/1') throw new Error(`unknown data schema ${data.schema}`);
  return data;
}

/// The index of the last element of the sorted `times` at or before `t` (0 before the first).
export function indexAtOrBefore(times, t) {
  let lo = 0;
  let hi = times.length - 1;
  if (hi < 0 || t <= times[0]) return 0;
  if (t >= times[hi]) return hi;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (times[mid] <= t) lo = mid;
    else hi = mid;
  }
  return lo;
}

/// Cumulative arc length [mm] along a polyline of [x, y, z] points.
export function arcLengths(points) {
  const out = new Float64Array(points.length);
  for (let i = 1; i < points.length; i++) {
    const a = points[i - 1];
    const b = points[i];
    out[i] = out[i - 1] + Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
  }
  return out;
}

/// The point of `points` at rest arc `arc_mm` (arcs from `restArcs`, the centerline at rest):
/// the box's and the truth's tip_path_mm are arcs at rest mapped onto the displaced colon.
export function pointAtArc(points, restArcs, arc_mm) {
  const n = points.length;
  if (n === 0) return [0, 0, 0];
  if (arc_mm <= 0) return points[0];
  if (arc_mm >= restArcs[n - 1]) return points[n - 1];
  const k = indexAtOrBefore(restArcs, arc_mm);
  const span = restArcs[k + 1] - restArcs[k];
  const w = span > 0 ? (arc_mm - restArcs[k]) / span : 0;
  const a = points[k];
  const b = points[k + 1];
  return [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])];
}

/// The alarms up at time t.
export function alarmsAt(alarms, t) {
  return alarms.filter((a) => a.start_s <= t && (a.end_s === null || t < a.end_s));
}

/// The first alarm raised after time t (by more than half a box period), or undefined.
export function nextAlarmAfter(alarms, t) {
  return alarms
    .filter((a) => a.start_s > t + 0.0025)
    .reduce((best, a) => (best === undefined || a.start_s < best.start_s ? a : best), undefined);
}
