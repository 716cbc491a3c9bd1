// The instructor station's map: the ice field (its open water too), its tiles and broken channel, the live
// floes (one path for all of them, built from typed arrays), the own ship with its track,
// other vessels, searchlight beams, a latitude/longitude grid and a scale bar. World
// coordinates: x east, y north, metres from the field's south-west corner as it was laid
// (a drifting field's ice is drawn moved by the frame header's ice_offset); north up.
"use strict";

const MAP_COLORS = {
  water: "#17364f", ice: "#d2dde6", pack: "#8fb0c8", convoy: "#ffd23f", tileLine: "rgba(70, 110, 140, 0.35)", frozenTile: "rgba(96, 130, 160, 0.10)",
  floe: "#f7fbfe", floeEdge: "#6d8aa1", frozenFloe: "#c3d1dc", track: "#ffb13b", ship: "#e8331f",
  shipEdge: "#ffffff", traffic: "#2fd27a", light: "rgba(255, 236, 140, 0.28)", grid: "rgba(255, 255, 255, 0.28)",
  gridText: "rgba(255, 255, 255, 0.85)", ghost: "rgba(255, 176, 59, 0.9)", region: "#ff7ad9", ridge: "#e040c0", brash: "#8596a6",
};

class MapView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.geo = null;
    this.tiles = new Map();     // placement -> {meta, holes: Path2D, floes: Path2D|null, box}
    this.floes = new Map();     // placement -> {cells, poses, path} of a live tile's free floes
    this.floeCount = 0;
    this.track = [];            // [x, y] pairs, NaN breaks the line
    this.frame = null;          // the last frame's header
    this.iceOffset = [0, 0];    // m: where the drifting ice field's frame lies in the world
    this.scale = 1.0;           // px per m
    this.cx = 0; this.cy = 0;   // world point in the middle
    this.follow = true;
    this.pick = null;           // callback while picking a position
    this.ghost = null;          // {x, y, heading} of a picked position
    this.plan = null;           // a debrief's whole track, drawn faint
    this.laidAreas = null;      // a debrief's areas of laid ice, as of its time
    this._dirty = false;
    this._drawSoon = () => { this._asked = false; if (this._dirty) this.draw(); };
    this.stats = { frames: 0, draws: 0, fps: 0, drawMs: 0, applyMs: 0, floes: 0, _t0: performance.now(), _n: 0 };
    window.stationStats = this.stats;
    this._input();
    this.dirty = true;
  }

  // a change to draw: drawn at the next animation frame (none is asked for while nothing
  // changes, so that an idle page leaves the CPU alone)
  get dirty() { return this._dirty; }

  set dirty(value) {
    this._dirty = value;
    if (value && !this._asked) { this._asked = true; requestAnimationFrame(this._drawSoon); }
  }

  // -- data ------------------------------------------------------------------------------
  setGeometry(header, arrays) {
    this.geo = { ...header, outline: arrays.outline, start: arrays.outline_start, centroid: arrays.centroid,
                 waterRuns: arrays.water_runs, brashRuns: arrays.brash_runs, regionPath: pathOf(arrays.region_xy, arrays.region_start, true),
                 ridgePath: pathOf(arrays.ridge_xy, arrays.ridge_start, false) };
    const f = header.field;
    this.width = f.nx * f.side; this.height = f.ny * f.side;
    this.tiles.clear(); this.floes.clear();
    this.dirty = true;
  }

  // a cell's outline, turned by yaw and moved to (x, y), as SVG path text (decimetres):
  // one Path2D made from the text of many cells is far quicker than a lineTo a corner
  _cell(g, x, y, yaw) {
    const o = this.geo.outline, a = this.geo.start[g], b = this.geo.start[g + 1];
    const c = Math.cos(yaw), s = Math.sin(yaw);
    let text = "M";
    for (let i = a; i < b; i++) {
      const px = o[2 * i], py = o[2 * i + 1];
      text += Math.round((x + c * px - s * py) * 10) / 10 + " " + Math.round((y + s * px + c * py) * 10) / 10 + (i + 1 < b ? "L" : "Z");
    }
    return text;
  }

  _setTile(meta, cells, floes) {
    const t = this.geo.templates[meta.template], side = t.side, turns = meta.turns % 4;
    const c = Math.round(Math.cos(turns * Math.PI / 2)), s = Math.round(Math.sin(turns * Math.PI / 2));
    const yaw = turns * Math.PI / 2, cen = this.geo.centroid;
    let holes = "", frozen = "";
    for (let i = 0; i < cells.length; i++) {
      const g = t.start + cells[i];
      const rx = cen[2 * g] - side / 2, ry = cen[2 * g + 1] - side / 2;
      holes += this._cell(g, c * rx - s * ry + side / 2 + meta.corner[0], s * rx + c * ry + side / 2 + meta.corner[1], yaw);
      if (floes.length) frozen += this._cell(g, floes[3 * i], floes[3 * i + 1], floes[3 * i + 2]);
    }
    this.tiles.set(meta.k, { meta, holes: new Path2D(holes), floes: frozen ? new Path2D(frozen) : null, side });
  }

  // the live floes, tile by tile: a tile's path is made again only when one of its floes moved
  _setFloes(list, cell, pose) {
    const kept = new Map();
    let at = 0;
    for (const [k, n] of list) {
      const cells = cell.subarray(at, at + n), poses = pose.subarray(3 * at, 3 * (at + n));
      at += n;
      const old = this.floes.get(k);
      if (old && sameArrays(old.cells, cells) && sameArrays(old.poses, poses)) { kept.set(k, old); continue; }
      let text = "";
      for (let i = 0; i < n; i++) text += this._cell(cells[i], poses[3 * i], poses[3 * i + 1], poses[3 * i + 2]);
      kept.set(k, { cells: cells.slice(), poses: poses.slice(), path: new Path2D(text) });
    }
    this.floes = kept;
  }

  applyFrame(header, arrays) {
    if (!this.geo) return;
    const t0 = performance.now();
    if (header.scene_reset) this.tiles.clear();
    let cellAt = 0, floeAt = 0;
    for (const meta of header.tiles) {
      const cells = arrays.tile_cells.subarray(cellAt, cellAt + meta.cells);
      const floes = arrays.tile_floes.subarray(floeAt, floeAt + 3 * meta.floes);
      cellAt += meta.cells; floeAt += 3 * meta.floes;
      this._setTile(meta, cells, floes);
    }
    this._setFloes(header.floe_tiles, arrays.floe_cell, arrays.floe_pose);
    this.floeCount = arrays.floe_cell.length;
    if (header.track_reset) this.track = [];
    const tr = arrays.track;
    for (let i = 0; i + 1 < tr.length; i += 2) this.track.push([tr[i], tr[i + 1]]);
    this.frame = header;
    this.iceOffset = header.ice_offset || [0, 0];
    if (this.follow) { this.cx = header.ship.east; this.cy = header.ship.north; }
    this.stats.frames++; this.stats.floes = this.floeCount; this.stats.applyMs = performance.now() - t0;
    this.dirty = true;
  }

  // a debrief's state: the ship as a frame header's ship, the track travelled so far, the
  // other own ships as traffic; the field as it was laid (the record holds what the
  // instruments got, not the ice's drift)
  showDebrief(ship, travelled, traffic = []) {
    this.frame = { ship, traffic };
    this.iceOffset = [0, 0];
    this.track = travelled;
    if (this.follow) { this.cx = ship.east; this.cy = ship.north; }
    this.stats.frames++;
    this.dirty = true;
  }

  // -- view ------------------------------------------------------------------------------
  toWorld(px, py) {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    return [this.cx + (px - w / 2) / this.scale, this.cy - (py - h / 2) / this.scale];
  }

  zoom(factor, px, py) {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (px === undefined) { px = w / 2; py = h / 2; }
    const [wx, wy] = this.toWorld(px, py);
    this.scale = Math.min(40, Math.max(0.02, this.scale * factor));
    if (!this.follow) { this.cx = wx - (px - w / 2) / this.scale; this.cy = wy + (py - h / 2) / this.scale; }
    this.dirty = true;
  }

  fitField() {
    if (!this.geo) return;
    this.setFollow(false);
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    this.cx = this.iceOffset[0] + this.width / 2; this.cy = this.iceOffset[1] + this.height / 2;
    this.scale = 0.9 * Math.min(w / this.width, h / this.height);
    this.dirty = true;
  }

  setFollow(on) {
    this.follow = on;
    document.getElementById("follow").classList.toggle("on", on);
    if (on && this.frame) { this.cx = this.frame.ship.east; this.cy = this.frame.ship.north; }
    this.dirty = true;
  }

  _input() {
    const cv = this.canvas;
    let drag = null;
    cv.addEventListener("wheel", (e) => { e.preventDefault(); this.zoom(Math.exp(-e.deltaY * 0.0015), e.offsetX, e.offsetY); },
      { passive: false });
    cv.addEventListener("mousedown", (e) => { drag = { x: e.offsetX, y: e.offsetY, moved: false }; });
    window.addEventListener("mouseup", () => { drag = null; });
    cv.addEventListener("mousemove", (e) => {
      const [wx, wy] = this.toWorld(e.offsetX, e.offsetY);
      document.getElementById("cursor-pos").textContent = this.geo ? `${formatLatLon(this.geo, wx, wy)}   N ${wy.toFixed(0)} m  E ${wx.toFixed(0)} m` : "";
      if (!drag || this.pick) return;
      const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 2) {
        if (this.follow) this.setFollow(false);
        this.cx -= dx / this.scale; this.cy += dy / this.scale;
        drag.x = e.offsetX; drag.y = e.offsetY; drag.moved = true; this.dirty = true;
      }
    });
    cv.addEventListener("click", (e) => {
      if (!this.pick) return;
      const [wx, wy] = this.toWorld(e.offsetX, e.offsetY);
      const done = this.pick; this.pick = null; cv.classList.remove("picking");
      done(wx, wy);
    });
    new ResizeObserver(() => { this.dirty = true; }).observe(cv);
  }

  // -- drawing ---------------------------------------------------------------------------
  draw() {
    const t0 = performance.now();
    const cv = this.canvas, ctx = this.ctx, dpr = window.devicePixelRatio || 1;
    const w = cv.clientWidth, h = cv.clientHeight;
    if (cv.width !== Math.round(w * dpr) || cv.height !== Math.round(h * dpr)) {
      cv.width = Math.round(w * dpr); cv.height = Math.round(h * dpr);
    }
    this.dirty = false;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = MAP_COLORS.water; ctx.fillRect(0, 0, w, h);
    if (!this.geo) return;
    const s = this.scale;
    const world = () => ctx.setTransform(dpr * s, 0, 0, -dpr * s, dpr * (w / 2 - this.cx * s), dpr * (h / 2 + this.cy * s));
    world();
    ctx.save(); ctx.translate(this.iceOffset[0], this.iceOffset[1]);  // the ice and its regions drift as one
    this._drawIce(ctx, s);
    this._drawRegions(ctx, s);
    ctx.restore();
    this._drawTrack(ctx, s);
    if (this.frame) {
      this._drawTraffic(ctx, s);
      if (this.geo.convoy) drawConvoy(ctx, s, this.geo.convoy, this.frame);
      this._drawShip(ctx, s, this.frame.ship, MAP_COLORS.ship, true);
    }
    if (this.ghost) this._drawGhost(ctx, s);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    this._drawRegionLabels(ctx, w, h);
    this._drawGrid(ctx, w, h);
    drawScale(ctx, h, this.scale);
    this._measure(t0);
  }

  _drawIce(ctx, s) {
    ctx.fillStyle = MAP_COLORS.ice; ctx.fillRect(0, 0, this.width, this.height);
    const runs = this.geo.waterRuns, side = this.geo.field.side;  // open-water tiles: (row, column, count)
    ctx.fillStyle = MAP_COLORS.water;
    for (let i = 0; i + 2 < runs.length; i += 3) ctx.fillRect(runs[i + 1] * side, runs[i] * side, runs[i + 2] * side, side);
    for (const [row, col, n, k] of (this.frame && this.frame.laid) || []) {  // the instructor's ice, by kind (brash stays over it)
      ctx.fillStyle = MAP_COLORS[(this.geo.ice_kinds || [])[k]] || MAP_COLORS.ice;
      ctx.fillRect(col * side, row * side, n * side, side);
    }
    if (this.laidAreas) drawLaidAreas(ctx, this.laidAreas, this.geo);  // a debrief's
    const brash = this.geo.brashRuns || [];  // tiles of brash alone: open water with brash on it
    ctx.fillStyle = MAP_COLORS.brash;
    for (let i = 0; i + 2 < brash.length; i += 3) {
      ctx.fillRect(brash[i + 1] * side, brash[i] * side, brash[i + 2] * side, side);
    }
    ctx.lineWidth = 1 / s;
    const frozen = new Path2D(), tileLines = new Path2D();
    for (const t of this.tiles.values()) {
      const [x, y] = t.meta.corner;
      tileLines.rect(x, y, t.side, t.side);
      if (t.meta.frozen) frozen.rect(x, y, t.side, t.side);
    }
    ctx.fillStyle = MAP_COLORS.frozenTile; ctx.fill(frozen);
    ctx.fillStyle = MAP_COLORS.water;
    for (const t of this.tiles.values()) ctx.fill(t.holes);
    ctx.strokeStyle = MAP_COLORS.tileLine; ctx.stroke(tileLines);
    ctx.strokeStyle = MAP_COLORS.floeEdge;
    ctx.fillStyle = MAP_COLORS.frozenFloe;
    for (const t of this.tiles.values()) if (t.floes) { ctx.fill(t.floes); if (s > 1) ctx.stroke(t.floes); }
    ctx.fillStyle = MAP_COLORS.floe;
    for (const f of this.floes.values()) { ctx.fill(f.path); if (s > 1) ctx.stroke(f.path); }
  }

  // the ice regions (a chart's and the config's) outlined, dashed, as they lie on the field;
  // the ridges' lines solid
  _drawRegions(ctx, s) {
    ctx.save();
    if (this.geo.ridgePath) {
      ctx.strokeStyle = MAP_COLORS.ridge; ctx.lineWidth = 3 / s; ctx.stroke(this.geo.ridgePath);
    }
    if (this.geo.regionPath) {
      ctx.strokeStyle = MAP_COLORS.region; ctx.lineWidth = 2 / s; ctx.setLineDash([10 / s, 6 / s]);
      ctx.stroke(this.geo.regionPath);
    }
    ctx.restore();
  }

  // each region's name and egg code at a point inside it (screen space, so the text stays upright)
  _drawRegionLabels(ctx, w, h) {
    ctx.font = "12px system-ui, sans-serif";
    for (const r of this.geo.regions || []) {
      if (!r.label) continue;
      const [x, y] = [r.label[0] + this.iceOffset[0], r.label[1] + this.iceOffset[1]];
      const px = w / 2 + (x - this.cx) * this.scale, py = h / 2 - (y - this.cy) * this.scale;
      if (px < -200 || py < -40 || px > w + 200 || py > h + 40) continue;
      const lines = [r.name, r.regime], width = Math.max(...lines.map((t) => ctx.measureText(t).width));
      ctx.fillStyle = "rgba(13, 24, 33, 0.7)"; ctx.fillRect(px - width / 2 - 4, py - 16, width + 8, 34);
      ctx.fillStyle = MAP_COLORS.region; ctx.textAlign = "center";
      lines.forEach((t, i) => ctx.fillText(t, px, py - 2 + 14 * i));
      ctx.textAlign = "start";
    }
  }

  _drawTrack(ctx, s) {
    if (this.plan) {
      ctx.beginPath();
      this.plan.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
      ctx.strokeStyle = "rgba(255, 177, 59, 0.35)"; ctx.lineWidth = 1.5 / s; ctx.stroke();
    }
    if (this.track.length < 2) return;
    ctx.beginPath();
    let pen = false;
    for (const [x, y] of this.track) {
      if (Number.isNaN(x)) { pen = false; continue; }
      if (pen) ctx.lineTo(x, y); else { ctx.moveTo(x, y); pen = true; }
    }
    if (this.frame && pen) ctx.lineTo(this.frame.ship.east, this.frame.ship.north);
    ctx.strokeStyle = MAP_COLORS.track; ctx.lineWidth = 2 / s; ctx.setLineDash([6 / s, 4 / s]); ctx.stroke();
    ctx.setLineDash([]);
  }

  // a hull (ship frame: x forward, y starboard) at (east, north) with heading (rad, from north clockwise)
  _hullPath(hull, east, north, heading, grow) {
    const sh = Math.sin(heading), ch = Math.cos(heading), p = new Path2D();
    hull.forEach(([a, b], i) => {
      const x = east + grow * (a * sh + b * ch), y = north + grow * (a * ch - b * sh);
      if (i === 0) p.moveTo(x, y); else p.lineTo(x, y);
    });
    p.closePath();
    return p;
  }

  _drawShip(ctx, s, ship, color, own) {
    const g = this.geo.ship, grow = Math.max(1, 26 / (g.length * s));  // at least 26 px long
    const env = this.frame.environment;
    if (own && env && env.visibility_m < 5000) {  // how far the bridge sees: the fog's circle
      ctx.beginPath(); ctx.arc(ship.east, ship.north, env.visibility_m, 0, 2 * Math.PI);
      ctx.strokeStyle = "rgba(255, 255, 255, 0.55)"; ctx.lineWidth = 1.5 / s; ctx.setLineDash([10 / s, 6 / s]); ctx.stroke();
      ctx.setLineDash([]);
    }
    for (const [on, bearing] of own ? ship.searchlights : []) {
      if (!on) continue;
      const a = ship.heading + bearing, reach = Math.max(300, 60 / s), spread = 0.12;
      ctx.beginPath(); ctx.moveTo(ship.east, ship.north);
      ctx.lineTo(ship.east + reach * Math.sin(a - spread), ship.north + reach * Math.cos(a - spread));
      ctx.lineTo(ship.east + reach * Math.sin(a + spread), ship.north + reach * Math.cos(a + spread));
      ctx.closePath(); ctx.fillStyle = MAP_COLORS.light; ctx.fill();
    }
    // heading line: one minute ahead at the speed over ground, along the course over ground
    const ahead = Math.max(ship.sog_kn * 0.5144 * 60, 0), cog = ship.cog_deg * Math.PI / 180;
    if (ahead > 1) {
      ctx.beginPath(); ctx.moveTo(ship.east, ship.north);
      ctx.lineTo(ship.east + ahead * Math.sin(cog), ship.north + ahead * Math.cos(cog));
      ctx.strokeStyle = "rgba(255,255,255,0.8)"; ctx.lineWidth = 1.5 / s; ctx.setLineDash([4 / s, 3 / s]); ctx.stroke();
      ctx.setLineDash([]);
    }
    const hull = this._hullPath(g.hull, ship.east, ship.north, ship.heading, grow);
    ctx.fillStyle = color; ctx.fill(hull);
    ctx.strokeStyle = MAP_COLORS.shipEdge; ctx.lineWidth = 1.5 / s; ctx.stroke(hull);
  }

  _drawTraffic(ctx, s) {
    for (const v of this.frame.traffic) {
      const length = v.length || 60, beam = v.beam || 12;
      const grow = Math.max(1, 18 / (length * s));
      const hull = [[length / 2, 0], [length / 4, beam / 2], [-length / 2, beam / 2], [-length / 2, -beam / 2],
        [length / 4, -beam / 2]];
      const p = this._hullPath(hull, v.x, v.y, v.heading, grow);
      ctx.fillStyle = MAP_COLORS.traffic; ctx.fill(p);
      ctx.strokeStyle = "#0b2a1a"; ctx.lineWidth = 1 / s; ctx.stroke(p);
      ctx.save(); ctx.translate(v.x, v.y); ctx.scale(1 / s, -1 / s);
      ctx.fillStyle = "#c8ffe0"; ctx.font = "11px system-ui, sans-serif";
      ctx.fillText(`${v.id}  ${v.speed_kn.toFixed(1)} kn`, 12, -10); ctx.restore();
    }
  }

  _drawGhost(ctx, s) {
    const g = this.ghost, p = this._hullPath(this.geo.ship.hull, g.x, g.y, g.heading * Math.PI / 180,
      Math.max(1, 26 / (this.geo.ship.length * s)));
    ctx.strokeStyle = MAP_COLORS.ghost; ctx.lineWidth = 2 / s; ctx.setLineDash([5 / s, 4 / s]); ctx.stroke(p);
    ctx.setLineDash([]);
  }

  _drawGrid(ctx, w, h) {
    const o = this.geo.origin;
    const [x0, y1] = this.toWorld(0, 0), [x1, y0] = this.toWorld(w, h);
    const lat = (y) => o.latitude_deg + y / o.m_per_deg_lat, lon = (x) => o.longitude_deg + x / o.m_per_deg_lon;
    const stepLat = niceAngle((lat(y1) - lat(y0)) / 5), stepLon = niceAngle((lon(x1) - lon(x0)) / 5);
    ctx.strokeStyle = MAP_COLORS.grid; ctx.lineWidth = 1; ctx.fillStyle = MAP_COLORS.gridText;
    ctx.font = "11px ui-monospace, 'DejaVu Sans Mono', monospace";
    ctx.beginPath();
    for (let a = Math.ceil(lat(y0) / stepLat) * stepLat; a <= lat(y1); a += stepLat) {
      const py = h / 2 - ((a - o.latitude_deg) * o.m_per_deg_lat - this.cy) * this.scale;
      ctx.moveTo(0, py); ctx.lineTo(w, py); ctx.fillText(formatAngle(a, "N", "S", 2), 4, py - 3);
    }
    for (let a = Math.ceil(lon(x0) / stepLon) * stepLon; a <= lon(x1); a += stepLon) {
      const px = w / 2 + ((a - o.longitude_deg) * o.m_per_deg_lon - this.cx) * this.scale;
      ctx.moveTo(px, 0); ctx.lineTo(px, h); ctx.fillText(formatAngle(a, "E", "W", 3), px + 3, 12);
    }
    ctx.stroke();
  }

  _measure(t0) {
    const st = this.stats, now = performance.now();
    st.draws++; st._n++; st.drawMs = now - t0;
    if (now - st._t0 >= 1000) { st.fps = st._n * 1000 / (now - st._t0); st._n = 0; st._t0 = now; }
  }
}
