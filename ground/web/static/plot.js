// Scrolling time plots and the top-down odometry trail, drawn on <canvas> (no library).

const DEG = 180 / Math.PI;
export { DEG };

// A value against time over the last `windowS` seconds; null values leave a gap.
export class ScrollingPlot {
  constructor(canvas, { windowS = 30, color = "#1565c0", digits = 2 } = {}) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.windowS = windowS;
    this.color = color;
    this.digits = digits;
    this.points = [];  // [t_s, value | null]
  }

  push(t, value) {
    this.points.push([t, value]);
    const start = t - this.windowS;
    let drop = 0;
    while (drop < this.points.length && this.points[drop][0] < start) drop++;
    if (drop > 0) this.points.splice(0, drop);
  }

  clear() { this.points = []; }

  draw(now) {
    const { ctx, canvas } = this;
    const w = canvas.width, h = canvas.height, pad = 4, left = 44;
    ctx.clearRect(0, 0, w, h);
    const values = this.points.filter(p => p[1] !== null).map(p => p[1]);
    ctx.fillStyle = "#555";
    ctx.font = "11px sans-serif";
    if (values.length === 0) {
      ctx.fillText("no data", left, h / 2);
      return;
    }
    let lo = Math.min(...values), hi = Math.max(...values);
    if (lo > 0 && lo < hi * 0.2) lo = 0;
    if (hi - lo < 1e-9) { const pad = Math.max(Math.abs(hi) * 0.25, 0.01); lo -= pad; hi += pad; }
    const t1 = now, t0 = now - this.windowS;
    const x = t => left + (t - t0) / (t1 - t0) * (w - left - pad);
    const y = v => h - pad - (v - lo) / (hi - lo) * (h - 2 * pad);
    ctx.fillText(hi.toFixed(this.digits), 2, 12);
    ctx.fillText(lo.toFixed(this.digits), 2, h - 4);
    if (lo < 0 && hi > 0) {
      ctx.strokeStyle = "#bbb";
      ctx.beginPath(); ctx.moveTo(left, y(0)); ctx.lineTo(w - pad, y(0)); ctx.stroke();
    }
    ctx.strokeStyle = this.color;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    let pen = false;
    for (const [t, v] of this.points) {
      if (v === null) { pen = false; continue; }
      if (pen) ctx.lineTo(x(t), y(v)); else ctx.moveTo(x(t), y(v));
      pen = true;
    }
    ctx.stroke();
    const last = values[values.length - 1];
    ctx.fillStyle = this.color;
    ctx.fillText(last.toFixed(this.digits), w - 50, 12);
  }
}

// The odometry trail seen from above: x forward (up the canvas at yaw 0 is to the right),
// y left; equal scale on both axes, fitted to the trail, a 1 m grid.
export class TrailView {
  constructor(canvas, maxPoints = 5000) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.maxPoints = maxPoints;
    this.points = [];  // [x_m, y_m]
    this.pose = null;  // [x_m, y_m, yaw_rad]
  }

  push(x, y, yaw) {
    if (x === null || y === null) return;
    const last = this.points[this.points.length - 1];
    if (!last || Math.hypot(x - last[0], y - last[1]) > 0.005) this.points.push([x, y]);
    if (this.points.length > this.maxPoints) this.points.shift();
    this.pose = [x, y, yaw ?? 0];
  }

  clear() { this.points = []; this.pose = null; }

  draw() {
    const { ctx, canvas } = this;
    const w = canvas.width, h = canvas.height, pad = 16;
    ctx.clearRect(0, 0, w, h);
    if (!this.pose) {
      ctx.fillStyle = "#555"; ctx.font = "11px sans-serif";
      ctx.fillText("no odometry", pad, h / 2);
      return;
    }
    const xs = this.points.map(p => p[0]), ys = this.points.map(p => p[1]);
    const xlo = Math.min(...xs) - 0.5, xhi = Math.max(...xs) + 0.5;
    const ylo = Math.min(...ys) - 0.5, yhi = Math.max(...ys) + 0.5;
    const scale = Math.min((w - 2 * pad) / (xhi - xlo), (h - 2 * pad) / (yhi - ylo));
    // Screen: odometry x to the right, odometry y (left) up.
    const cx = (xlo + xhi) / 2, cy = (ylo + yhi) / 2;
    const sx = x => w / 2 + (x - cx) * scale, sy = y => h / 2 - (y - cy) * scale;
    ctx.strokeStyle = "#eee"; ctx.lineWidth = 1;
    for (let g = Math.ceil(cx - w / 2 / scale); g <= cx + w / 2 / scale; g++) {
      ctx.beginPath(); ctx.moveTo(sx(g), 0); ctx.lineTo(sx(g), h); ctx.stroke();
    }
    for (let g = Math.ceil(cy - h / 2 / scale); g <= cy + h / 2 / scale; g++) {
      ctx.beginPath(); ctx.moveTo(0, sy(g)); ctx.lineTo(w, sy(g)); ctx.stroke();
    }
    ctx.strokeStyle = "#1565c0"; ctx.lineWidth = 2;
    ctx.beginPath();
    this.points.forEach(([x, y], i) => (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
    ctx.stroke();
    const [x, y, yaw] = this.pose;
    ctx.save();
    ctx.translate(sx(x), sy(y));
    ctx.rotate(-yaw);
    ctx.fillStyle = "#e65100";
    ctx.beginPath(); ctx.moveTo(10, 0); ctx.lineTo(-6, 6); ctx.lineTo(-6, -6); ctx.closePath();
    ctx.fill();
    ctx.restore();
  }
}
