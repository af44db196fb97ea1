// fusetrack fusion node dashboard: read-only; draws the field, sensors (with fields of view),
// the tracks (one, or several with the association layer) with their 2-sigma ellipses and
// trails; lists each sensor's last reading and its age.
// Data: WebSocket /ws/tracks (one frame per tick) and polling /sensors and /health.
"use strict";

const state = { area: [0, 100, 0, 100], sensors: [], tracks: [], trails: new Map(), tick: null,
                time: null, health: null };
const COLORS = ["#c81e1e", "#1e7a1e", "#7a1ec8", "#c8781e", "#1e9ac8", "#c81e9a"];
const colorOf = (id) => COLORS[(id - 1) % COLORS.length];
const MAX_TRAIL = 600;

function remember(id, position) {
  if (!state.trails.has(id)) state.trails.set(id, []);
  const trail = state.trails.get(id);
  trail.push(position);
  if (trail.length > MAX_TRAIL) trail.shift();
}
const canvas = document.getElementById("field");
const ctx = canvas.getContext("2d");
const $ = (id) => document.getElementById(id);
const fmt = (v, d = 2) => (v === null || v === undefined ? "–" : Number(v).toFixed(d));

function view() {
  const [x0, x1, y0, y1] = state.area;
  const pad = 0.08 * Math.max(x1 - x0, y1 - y0);
  const w = x1 - x0 + 2 * pad, h = y1 - y0 + 2 * pad;
  const s = Math.min(canvas.width / w, canvas.height / h);
  return {
    s,
    px: (x) => (x - x0 + pad) * s,
    py: (y) => canvas.height - (y - y0 + pad) * s,
  };
}

function ellipse(v, mean, cov, color) {
  // 2-sigma ellipse of a 2x2 covariance: eigen-decomposition in closed form
  const a = cov[0][0], b = cov[0][1], c = cov[1][1];
  const tr = (a + c) / 2, det = Math.sqrt(Math.max(0, ((a - c) / 2) ** 2 + b * b));
  const l1 = tr + det, l2 = Math.max(0, tr - det);
  const ang = Math.atan2(l1 - a, b || 1e-12);
  ctx.beginPath();
  ctx.ellipse(v.px(mean[0]), v.py(mean[1]), 2 * Math.sqrt(l1) * v.s, 2 * Math.sqrt(l2) * v.s,
              -ang, 0, 2 * Math.PI);
  ctx.strokeStyle = color; ctx.lineWidth = 1.5; ctx.stroke();
}

function draw() {
  const v = view();
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const [x0, x1, y0, y1] = state.area;
  ctx.strokeStyle = "#999"; ctx.setLineDash([4, 4]);
  ctx.strokeRect(v.px(x0), v.py(y1), (x1 - x0) * v.s, (y1 - y0) * v.s);
  ctx.setLineDash([]);
  const reach = 0.35 * Math.max(x1 - x0, y1 - y0);
  for (const s of state.sensors) {
    const recent = s.last && s.last.age < 5;
    if (s.kind === "position_fix" && recent) { // a position fix: an orange dot where it says
      ctx.fillStyle = "#e08a00";
      ctx.beginPath(); ctx.arc(v.px(s.last.value[0]), v.py(s.last.value[1]), 4, 0, 2 * Math.PI); ctx.fill();
    }
    if (!s.position) continue;
    const [sx, sy] = s.position;
    const r = (s.max_range ? Math.min(s.max_range, reach) : reach) * v.s;
    ctx.fillStyle = "rgba(70,130,180,0.10)";
    ctx.beginPath();
    if (s.fov < 2 * Math.PI - 1e-6) {
      ctx.moveTo(v.px(sx), v.py(sy));
      ctx.arc(v.px(sx), v.py(sy), r, -(s.heading + s.fov / 2), -(s.heading - s.fov / 2));
      ctx.closePath();
    } else {
      ctx.arc(v.px(sx), v.py(sy), r, 0, 2 * Math.PI);
    }
    ctx.fill();
    const age = s.last ? s.last.age : Infinity;
    ctx.fillStyle = age < 5 ? "#2a6db0" : "#b00";
    ctx.fillRect(v.px(sx) - 5, v.py(sy) - 5, 10, 10);
    ctx.fillStyle = "#222";
    ctx.fillText(s.id, v.px(sx) + 8, v.py(sy) - 8);
    const ray = s.kind === "bearing" ? s.heading + (s.last ? s.last.value[0] : 0)
      : s.kind === "detection_function" && s.last ? s.last.peak_direction : null;
    if (ray !== null && s.last && age < 5) { // the last bearing (or detection peak) as a ray
      const th = ray;
      ctx.strokeStyle = "rgba(42,109,176,0.5)";
      ctx.beginPath(); ctx.moveTo(v.px(sx), v.py(sy));
      ctx.lineTo(v.px(sx + 2 * reach * Math.cos(th)), v.py(sy + 2 * reach * Math.sin(th)));
      ctx.stroke();
    }
  }
  for (const [id, trail] of state.trails) {
    if (trail.length < 2) continue;
    ctx.strokeStyle = colorOf(id); ctx.globalAlpha = 0.6; ctx.lineWidth = 2; ctx.beginPath();
    trail.forEach((p, i) => (i ? ctx.lineTo : ctx.moveTo).call(ctx, v.px(p[0]), v.py(p[1])));
    ctx.stroke(); ctx.lineWidth = 1; ctx.globalAlpha = 1;
  }
  for (const t of state.tracks) {
    ctx.fillStyle = colorOf(t.track);
    ctx.beginPath(); ctx.arc(v.px(t.position[0]), v.py(t.position[1]), 5, 0, 2 * Math.PI); ctx.fill();
    ellipse(v, t.position, t.position_covariance, colorOf(t.track));
    if (state.tracks.length > 1) ctx.fillText(`#${t.track}`, v.px(t.position[0]) + 7, v.py(t.position[1]) + 12);
  }
}

function showTrack() {
  if (state.tick === null) return;
  $("tick").textContent = state.tick;
  $("time").textContent = fmt(state.time, 1);
  const ts = state.tracks;
  if (ts.length === 0) {
    $("track").innerHTML = "<tr><td>no track this tick</td></tr>";
  } else if (ts.length === 1) {
    const t = ts[0];
    const sd = t.position_covariance.map((row, i) => Math.sqrt(row[i]));
    $("track").innerHTML =
      `<tr><th>position (m)</th><td>${fmt(t.position[0])}, ${fmt(t.position[1])}</td></tr>` +
      `<tr><th>σ (m)</th><td>${fmt(sd[0])}, ${fmt(sd[1])}</td></tr>` +
      `<tr><th>state</th><td>${t.state.map((x) => fmt(x, 3)).join(", ")}</td></tr>` +
      `<tr><th>fused this tick</th><td>${t.readings} from ${t.sensors.join(", ") || "none"}</td></tr>`;
  } else {
    $("track").innerHTML = `<tr><th>track</th><th>position (m)</th><th>σ (m)</th></tr>` +
      ts.map((t) => {
        const sd = t.position_covariance.map((row, i) => Math.sqrt(row[i]));
        return `<tr class="track"><td style="color:${colorOf(t.track)}">#${t.track}</td>` +
               `<td>${fmt(t.position[0])}, ${fmt(t.position[1])}</td>` +
               `<td>${fmt(sd[0])}, ${fmt(sd[1])}</td></tr>`;
      }).join("") +
      `<tr><th>fused this tick</th><td colspan="2">${ts[0].readings} readings</td></tr>`;
  }
}

function showSensors() {
  $("sensors").innerHTML = state.sensors.map((s) => {
    const age = s.last ? s.last.age : null;
    const vals = s.last ? s.last.value : null;
    const value = !vals ? "none" : vals.length > 6 // a detection function: its size and peak
      ? `${vals.length} values, peak ${fmt(Math.max(...vals), 3)} at #${vals.indexOf(Math.max(...vals))}`
      : vals.map((x) => fmt(x, 3)).join(", ");
    const cls = age === null || age > 5 ? ' class="silent"' : "";
    return `<tr${cls}><td>${s.id}</td><td>${s.kind}</td><td>${s.node}</td><td>${value}</td>` +
           `<td>${age === null ? "never" : fmt(age, 1)}</td><td>${s.accepted}</td></tr>`;
  }).join("");
}

function showHealth() {
  const h = state.health;
  if (!h) return;
  $("status").textContent = h.status; $("status").className = h.status;
  $("rate").textContent = fmt(h.messages_per_second, 1);
  $("accepted").textContent = h.accepted;
  const reasons = Object.entries(h.rejected).filter(([, n]) => n > 0);
  $("rejected").textContent = reasons.reduce((a, [, n]) => a + n, 0);
  $("reasons").innerHTML = reasons.length
    ? reasons.map(([r, n]) => `<tr><td>${r}</td><td>${n}</td></tr>`).join("")
    : "<tr><td>none</td></tr>";
}

// a node with readers configured needs a token: open the dashboard as /?token=READER_TOKEN
const token = new URLSearchParams(location.search).get("token");
const auth = token ? `?token=${encodeURIComponent(token)}` : "";

async function poll() {
  try {
    const [s, h] = await Promise.all([fetch(`/sensors${auth}`), fetch(`/health${auth}`)]);
    const sj = await s.json();
    state.area = sj.area; state.sensors = sj.sensors; state.health = await h.json();
    showSensors(); showHealth(); draw();
  } catch (e) {
    $("status").textContent = "unreachable"; $("status").className = "down";
  }
}

function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws/tracks${auth}`);
  ws.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "hello") {
      state.area = msg.area;
      state.trails = new Map();
      for (const h of msg.history) remember(h.track ?? 1, h.position);
      state.tracks = msg.tracks;
      if (msg.tracks.length) { state.tick = msg.tracks[0].tick; state.time = msg.tracks[0].time; }
    } else if (msg.type === "tick") {
      state.tracks = msg.tracks ?? (msg.track ? [msg.track] : []);
      state.tick = msg.tick ?? (msg.track && msg.track.tick);
      state.time = msg.time ?? (msg.track && msg.track.time);
      for (const t of state.tracks) remember(t.track, t.position);
    }
    showTrack(); draw();
  };
  ws.onclose = () => setTimeout(connect, 1000);
}

poll();
setInterval(poll, 1000);
connect();
