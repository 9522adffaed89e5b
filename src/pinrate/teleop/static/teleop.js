// pinrate teleop console: the Meshcat viewer built here, one WebSocket to the server.
// Input out (held keys by physical code, gamepad axes and buttons, speed; every 50 ms as the
// heartbeat and at every change); scene commands (binary, meshcat's own) and JSON frames in.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const viewer = new MeshCat.Viewer($("viewer"));
  window.viewer = viewer;
  const HEARTBEAT_MS = 50;
  const ACTION_KEYS = { Space: "halt-toggle", KeyB: "reverse", KeyR: "record-toggle", KeyH: "home" };

  // What the page knows; tests and the benchmark read it (window.pinrate).
  const state = {
    hello: null, controlling: false, free: false, moveKeys: new Set(), held: new Set(),
    seq: 0, keySeq: 0, keyTime: null, latencies: [], frames: 0, last: null, speed: 1,
    halted: false, recording: false, events: [], connected: false, said: [],
  };
  window.pinrate = state;

  // Off loopback the server printed a URL with a token: the socket carries it too.
  const token = new URLSearchParams(location.search).get("token");
  const socket = new WebSocket(`ws://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : ""));
  socket.binaryType = "arraybuffer";
  // Every message carries the page's clock: the server ages commands from their sending.
  const send = (message) => {
    if (socket.readyState === 1) socket.send(JSON.stringify({ ...message, sent: performance.now() }));
  };
  socket.onopen = () => { state.connected = true; };
  socket.onclose = () => {
    state.connected = false;
    $("role").textContent = "disconnected: the server is gone (reload when it is back)";
    $("role").className = "role watching";
  };
  socket.onmessage = (event) => {
    if (typeof event.data !== "string") {
      viewer.handle_command_bytearray(new Uint8Array(event.data));
      return;
    }
    const message = JSON.parse(event.data);
    if (message.type === "frame") onFrame(message);
    else if (message.type === "hello") onHello(message);
    else if (message.type === "role") onRole(message);
    else if (message.type === "event") onEvent(message);
  };

  // ---------------------------------------------------------------- input
  function gamepad() {
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    for (const pad of pads) {
      if (pad && pad.connected !== false) {
        return {
          id: pad.id,
          axes: Array.from(pad.axes, Number),
          buttons: Array.from(pad.buttons, (b) => (typeof b === "number" ? b : b.value)),
        };
      }
    }
    return null;
  }

  function sendInput() {
    if (!state.controlling) return;
    const pad = gamepad();
    state.seq += 1;
    send({ type: "input", seq: state.seq, keys: [...state.held], axes: pad ? pad.axes : [],
           buttons: pad ? pad.buttons : [], speed: state.speed });
  }
  setInterval(sendInput, HEARTBEAT_MS);  // the heartbeat: a frozen page stops the robot

  let lastPad = "null";
  function pollPad() {  // Chrome's gamepads are snapshots: poll every animation frame
    const pad = gamepad();
    const text = JSON.stringify(pad && [pad.axes, pad.buttons]);
    if (text !== lastPad) {
      if (state.keyTime === null && pad && pad.axes.some((a) => Math.abs(a) > 0.5)) {
        state.keySeq = state.seq + 1;
        state.keyTime = performance.now();
      }
      lastPad = text;
      sendInput();
    }
    $("pad").textContent = pad ? `gamepad: ${pad.id}` : "no gamepad";
    requestAnimationFrame(pollPad);
  }
  requestAnimationFrame(pollPad);
  window.addEventListener("gamepadconnected", () => sendInput());

  function clearKeys() {
    if (state.held.size) { state.held.clear(); sendInput(); }
  }
  window.addEventListener("keydown", (event) => {
    if (state.moveKeys.has(event.code)) {
      event.preventDefault();
      if (!state.held.has(event.code)) {
        state.held.add(event.code);
        state.keySeq = state.seq + 1;
        state.keyTime = performance.now();
        sendInput();
      }
      return;
    }
    const action = ACTION_KEYS[event.code];
    if (!action || event.repeat) return;
    event.preventDefault();
    if (action === "halt-toggle") act(state.halted ? "resume" : "halt");
    else if (action === "record-toggle") act("record", { on: !state.recording });
    else act(action);
  });
  window.addEventListener("keyup", (event) => {
    if (state.held.delete(event.code)) sendInput();
  });
  window.addEventListener("blur", clearKeys);
  document.addEventListener("visibilitychange", () => { if (document.hidden) clearKeys(); });

  function act(type, extra = {}) { send({ type, ...extra }); }
  $("halt").onclick = () => act(state.halted ? "resume" : "halt");
  $("reverse").onclick = () => act("reverse");
  $("record").onclick = () => act("record", { on: !state.recording });
  $("home").onclick = () => act("home");
  $("claim").onclick = () => act("claim");
  for (const id of ["frame-hand", "frame-base"]) $(id).onclick = (e) => act("frame", { frame: e.target.dataset.frame });
  $("singularity").onchange = (e) => act("configure", { singularity: e.target.value });
  $("wrist").onchange = (e) => act("configure", { wrist: e.target.value });
  $("speed").oninput = (e) => {
    state.speed = Number(e.target.value) / 100;
    $("speed-value").textContent = `${e.target.value} %`;
    sendInput();
  };
  // Buttons keep no focus, so Space never "clicks" the last one pressed.
  for (const button of document.querySelectorAll("button, select")) button.addEventListener("focus", (e) => {
    if (e.target.tagName === "BUTTON") e.target.blur();
  });

  // ---------------------------------------------------------------- what arrives
  function onHello(hello) {
    state.hello = hello;
    state.moveKeys = new Set(hello.keys);
    $("robot").textContent = `· ${hello.robot}`;
    document.title = `pinrate teleop · ${hello.robot}`;
    for (const [id, names, chosen] of [["singularity", hello.singularities, hello.singularity],
                                       ["wrist", hello.wrists, hello.wrist]]) {
      $(id).replaceChildren(...names.map((name) => new Option(name, name, false, name === chosen)));
    }
    const joints = $("joints");
    joints.replaceChildren();
    hello.joints.forEach((joint, index) => {
      const row = document.createElement("div");
      row.className = "joint";
      row.id = `joint-${index}`;
      row.dataset.name = joint.name;
      row.innerHTML = `<span class="name" title="${joint.name}">${joint.name}</span>` +
        `<div class="bar${joint.lower === null ? " unlimited" : ""}"><div class="marker"></div></div>` +
        `<span class="value"></span>`;
      joints.appendChild(row);
    });
  }

  function onRole(role) {
    state.controlling = role.controlling;
    state.free = role.free;
    $("role").textContent = role.controlling ? "you control the robot" :
      role.free ? "watching: nobody controls the robot" : "watching: another page controls the robot";
    $("role").className = role.controlling ? "role" : "role watching";
    $("claim").hidden = role.controlling || !role.free;
    if (role.controlling) sendInput();
  }

  function onEvent(event) {
    state.events.push(event);
    const line = document.createElement("div");
    line.className = event.level;
    line.textContent = event.text + " ";
    for (const link of event.links || []) {
      const a = document.createElement("a");
      a.href = link;
      a.textContent = link.split("/").pop();
      a.download = "";
      line.append(a, " ");
    }
    $("events").prepend(line);
    while ($("events").children.length > 8) $("events").lastChild.remove();
  }

  const format = (value, digits = 3) => (value === null || value === undefined ? "–" : Number(value).toFixed(digits));

  function onFrame(frame) {
    state.frames += 1;
    state.last = frame;
    state.halted = frame.halted;
    state.recording = frame.recording;
    if (frame.poses) {
      for (const [path, matrix] of Object.entries(frame.poses)) {
        viewer.handle_command({ type: "set_transform", path: `/meshcat/${path}`, matrix: new Float32Array(matrix) });
      }
      if (state.keyTime !== null && frame.input_seq >= state.keySeq && frame.moving) {
        const pressed = state.keyTime;
        state.keyTime = null;
        requestAnimationFrame(() => state.latencies.push(performance.now() - pressed));
      }
    }
    const previous = state.said[state.said.length - 1];
    if (!previous || previous.word !== frame.status || previous.detail !== frame.detail) {
      state.said.push({ word: frame.status, detail: frame.detail, time: performance.now() });
      if (state.said.length > 500) state.said.shift();
    }
    $("status").style.background = frame.colour;
    $("status-word").textContent = frame.status;
    $("status-detail").textContent = frame.detail;
    $("rho").textContent = format(frame.rho);
    $("conditioning").textContent = frame.conditioning ?
      `${format(frame.conditioning.value)} (${frame.conditioning.block})` : "–";
    $("rate").textContent = `${format(frame.loop.rate, 0)} Hz`;
    $("p99").textContent = `${format(frame.loop.p99_ms, 2)} ms`;
    $("halt").textContent = frame.halted ? "resume" : "halt";
    $("halt").classList.toggle("on", frame.halted);
    $("record").textContent = frame.recording ? "stop recording" : "record";
    $("record").classList.toggle("on", frame.recording);
    $("reverse").classList.toggle("on", frame.reversing);
    $("frame-hand").classList.toggle("chosen", frame.frame === "hand");
    $("frame-base").classList.toggle("chosen", frame.frame === "base");
    if ($("singularity").value !== frame.singularity) $("singularity").value = frame.singularity;
    if ($("wrist").value !== frame.wrist) $("wrist").value = frame.wrist;
    if (frame.twist && state.hello) {
      const names = state.hello.controls;
      const parts = names.map((name, i) => `${name} ${format(frame.twist[i]).padStart(7)}`);
      const linear = names.filter((name) => name.startsWith("v")).length;  // m/s, then rad/s
      $("command").textContent = `${parts.slice(0, linear).join("  ")}\n${parts.slice(linear).join("  ")}`;
    }
    if (state.hello) {
      const frozen = new Set(frame.frozen);
      state.hello.joints.forEach((joint, index) => {
        const row = $(`joint-${index}`);
        const value = frame.q[index];
        row.querySelector(".value").textContent = value === null ? "–" : format(value, 3);
        let share = 0.5;
        if (joint.lower !== null && value !== null) share = (value - joint.lower) / (joint.upper - joint.lower);
        else if (value !== null) share = 0.5 + Math.atan(value) / Math.PI;
        row.querySelector(".marker").style.left = `${Math.min(Math.max(share, 0), 1) * 100}%`;
        const near = joint.lower !== null && (share < 0.03 || share > 0.97);
        row.classList.toggle("near", near);
        row.classList.toggle("limit", joint.lower !== null && (share <= 1e-6 || share >= 1 - 1e-6));
        row.classList.toggle("held", frozen.has(joint.name));
      });
    }
  }
})();
