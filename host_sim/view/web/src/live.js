// A live run (`scopekin simulate --view`): the server's messages (server-sent events on /events)
// appended to the page's data as they come: the timeline's rows, the shapes, the alarms and fault
// flags as intervals from the rows' flags.

const kAlarmFlags = [
  ['self_lock', (row) => row.self_lock === 1],
  ['contact_force_warning', (row) => row.contact_level === 1],
  ['contact_force_critical', (row) => row.contact_level >= 2],
];

/// Opens or closes the interval of `key` at time t; returns the interval opened, if any.
function track(list, open, key, up, t, make) {
  if (up && !open[key]) {
    const item = { ...make(), start_s: t, end_s: null };
    list.push(item);
    open[key] = item;
    return item;
  }
  if (!up && open[key]) {
    open[key].end_s = t;
    delete open[key];
  }
  return undefined;
}

export function appendRows(data, rows, open) {
  const s = data.series;
  const opened = [];
  for (const row of rows) {
    for (const key of ['time_s', 'handle_force_N', 'handle_torque_Nmm', 'insertion_mm', 'true_tip_path_mm',
      'box_tip_path_mm', 'box_tip_sd_mm', 'true_max_force_N', 'box_max_force_N'])
      s[key].push(row[key] ?? null);
    s.station_path_mm.push(row.stations.map((st) => st[0]));
    s.station_normal_N.push(row.stations.map((st) => st[1]));
    const t = row.time_s;
    for (const [kind, up] of kAlarmFlags) {
      const a = track(data.alarms, open.alarms, kind, up(row), t, () => ({ kind }));
      if (a) opened.push(a);
    }
    (data.fault_names || []).forEach((flag, bit) =>
      track(data.faults, open.faults, flag, ((row.fault_flags >>> bit) & 1) === 1, t, () => ({ flag })));
  }
  return opened;
}

/// Subscribes `view` to the server's live messages.
export function connectLive(view) {
  const open = { alarms: {}, faults: {} };
  const source = new EventSource('events');
  source.onmessage = (event) => {
    const message = JSON.parse(event.data);
    view.messagesReceived += 1;
    const opened = message.rows ? appendRows(view.data, message.rows, open) : [];
    if (message.frame) {
      message.frame.label = '';
      view.data.frames.push(message.frame);
      view.frameTimes.push(message.frame.time_s);
    }
    if (message.done) source.close();
    view.liveUpdate(opened, message.done === true, message.replay === true);
  };
  source.onerror = () => {
    if (source.readyState === EventSource.CLOSED) view.liveUpdate([], true, false);
  };
  return source;
}
