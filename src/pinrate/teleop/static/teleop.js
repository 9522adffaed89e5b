// pinrate teleop console: the Meshcat viewer built here, one WebSocket to the server, owned
// by a dedicated worker (static/heartbeat.js) that sends the heartbeat on its own schedule, so
// a main thread blocked by rendering does not trip the dead man (a frozen one does, after the
// server's freeze limit). Input out (held keys by physical code, gamepad axes and buttons,
// speed; posted to the worker at every change, the worker sends it at once and every 50 ms);
// scene commands (binary, meshcat's own) and JSON frames in, through the worker.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const viewer = new MeshCat.Viewer($("viewer"));
  window.viewer = viewer;
  const ALIVE_MS = 50;
  // Space and Escape only stop (never a toggle: a double press stays stopped); resume is the
  // resume button's alone, a click no key repeat can make.
  const ACTION_KEYS = { Space: "halt", Escape: "halt", KeyB: "reverse", KeyR: "record-toggle", KeyH: "home" };

  // What the page knows; tests and the benchmark read it (window.pinrate).
  const state = {
    hello: null, controlling: false, free: false, moveKeys: new Set(), held: new Set(),
    seq: 0, keySeq: 0, keyTime: null, latencies: [], frames: 0, last: null, speed: 1,
    halted: false, recording: false, events: [], connected: false, said: [], keyLog: [],
    jog: {}, jogLog: [], hid: [0, 0, 0, 0, 0, 0], hidLog: [],
  };
  window.pinrate = state;

  // Off loopback the server printed a URL with a token: the socket carries it too.
  const token = new URLSearchParams(location.search).get("token");
  const worker = new Worker("static/heartbeat.js");
  worker.postMessage({
    type: "connect",
    url: `ws://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : ""),
  });
  // The worker stamps every message (sent: its clock; alive: when this thread last spoke).
  const send = (message) => worker.postMessage({ type: "send", message });
  worker.onmessage = (event) => {
    const data = event.data;
    if (data.kind === "binary") viewer.handle_command_bytearray(new Uint8Array(data.data));
    else if (data.kind === "message") {
      const message = data.message;
      if (message.type === "frame") onFrame(message);
      else if (message.type === "hello") onHello(message);
      else if (message.type === "role") onRole(message);
      else if (message.type === "event") onEvent(message);
    } else if (data.kind === "open") state.connected = true;
    else if (data.kind === "closed") {
      state.connected = false;
      $("role").textContent = "disconnected: the server is gone (reload when it is back)";
      $("role").className = "role watching";
    }
  };

  // ---------------------------------------------------------------- input
  // A SpaceMouse that the browser offers as a gamepad has no standard layout: its axes are
  // the cap's six (translation then rotation), not two sticks, so read as a pad its
  // translation would turn the hand. It is ignored as a gamepad (and said so); WebHID reads it.
  const spaceMouseLike = (pad) => pad.mapping !== "standard" && /3dconnexion|spacemouse|space ?navigator/i.test(pad.id);
  state.ignoredPads = [];
  function gamepad() {
    if (document.hidden) return null;  // a hidden page drives nothing
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    state.ignoredPads = [];
    for (const pad of pads) {
      if (pad && pad.connected !== false && spaceMouseLike(pad)) state.ignoredPads.push(pad.id);
      else if (pad && pad.connected !== false) {
        return {
          id: pad.id,
          axes: Array.from(pad.axes, Number),
          buttons: Array.from(pad.buttons, (b) => (typeof b === "number" ? b : b.value)),
        };
      }
    }
    return null;
  }

  // The held input, to the worker: sent at once and then as the heartbeat's payload.
  function sendInput() {
    if (!state.controlling) return;
    const pad = gamepad();
    state.seq += 1;
    worker.postMessage({ type: "input", input: {
      type: "input", seq: state.seq, keys: [...state.held], axes: pad ? pad.axes : [],
      buttons: pad ? pad.buttons : [], speed: state.speed, jog: { ...state.jog }, hid: state.hid.slice(),
    } });
  }

  // Chrome's gamepads are snapshots: polled every animation frame and every ALIVE_MS; a
  // change goes out at once, otherwise the poll is the main thread's sign of life.
  let lastPad = "null";
  let polledAt = performance.now();
  function poll() {
    const now = performance.now();
    // The device's silence is counted over the time this thread ran: a block (software
    // rendering) holds its reports back too, so a block counts for at most 4 ALIVE_MS, and
    // a page that blocks every frame still stops a silent cap (a frozen page: the server's
    // freeze rule).
    hidSilence += Math.min(now - polledAt, 4 * ALIVE_MS);
    polledAt = now;
    if (hidDevice && state.hid.some(Boolean) && hidSilence > HID_STALE_MS) {
      state.hid = [0, 0, 0, 0, 0, 0];
      $("spacemouse").textContent = `SpaceMouse silent for ${HID_STALE_MS} ms while deflected: stopped`;
      sendInput();
    }
    const pad = gamepad();
    const text = JSON.stringify(pad && [pad.axes, pad.buttons]);
    if (text !== lastPad) {
      if (state.keyTime === null && pad && pad.axes.some((a) => Math.abs(a) > 0.5)) {
        state.keySeq = state.seq + 1;
        state.keyTime = performance.now();
      }
      lastPad = text;
      sendInput();
    } else worker.postMessage({ type: "alive" });
    return pad;
  }
  function pollFrame() {
    const pad = poll();
    const ignored = state.ignoredPads.map((id) => `${id}: ignored as a gamepad (not a standard layout: ` +
      "its axes are the cap's, not sticks); use connect SpaceMouse").join("; ");
    $("pad").textContent = [pad ? `gamepad: ${pad.id}` : ignored ? "" : "no gamepad", ignored].filter(Boolean).join("; ");
    requestAnimationFrame(pollFrame);
  }
  requestAnimationFrame(pollFrame);
  setInterval(poll, ALIVE_MS);
  window.addEventListener("gamepadconnected", () => sendInput());

  // ---------------------------------------------------------------- SpaceMouse (WebHID)
  // 3Dconnexion's devices (vendor 0x256f; older ones Logitech's 0x046d), multi-axis
  // controllers (usage page 1, usage 8). Reports: id 1 = translation x, y, z (int16 LE),
  // id 2 = rotation rx, ry, rz; newer models send all six in one 12-byte report id 1. The raw
  // counts go to the server, whose mapping (pinrate.teleop.mapping.spacemouse) applies the
  // dead zone, the full scale (±350) and the hand axes. Sent at most every HID_MS (a device
  // reports at 60-125 Hz), and as the heartbeat's payload.
  const HID_MS = 25;
  // A deflected cap reports continuously (every 8-16 ms); one silent this long while its last
  // counts were not zero (a USB hiccup, a dying battery) counts as released.
  const HID_STALE_MS = 500;
  const SPACEMOUSE_FILTERS = [0x256f, 0x046d].map((vendorId) => ({ vendorId, usagePage: 0x01, usage: 0x08 }));
  let hidDevice = null;
  let hidPending = null;
  let hidSentAt = -Infinity;
  let hidSilence = 0;  // ms of this thread's time since the device's last report
  function onReport(event) {
    hidSilence = 0;
    const data = event.data;
    const count = (i) => data.getInt16(2 * i, true);
    const before = state.hid.join();
    if (event.reportId === 1 && data.byteLength >= 12) state.hid = [0, 1, 2, 3, 4, 5].map(count);
    else if (event.reportId === 1 && data.byteLength >= 6) state.hid = [count(0), count(1), count(2), ...state.hid.slice(3)];
    else if (event.reportId === 2 && data.byteLength >= 6) state.hid = [...state.hid.slice(0, 3), count(0), count(1), count(2)];
    else return;  // buttons, battery, ...
    if (state.hid.join() === before) return;
    state.hidLog.push({ at: performance.now(), hid: state.hid.slice() });
    if (state.hidLog.length > 1000) state.hidLog.shift();
    // at once when the last went out HID_MS ago or the cap is released (a stop never waits),
    // otherwise once the HID_MS are up, with the latest counts
    const now = performance.now();
    const flush = () => { hidPending = null; hidSentAt = performance.now(); sendInput(); };
    if (!state.hid.some(Boolean) || now - hidSentAt >= HID_MS) {
      clearTimeout(hidPending);
      flush();
    } else if (hidPending === null) hidPending = setTimeout(flush, HID_MS - (now - hidSentAt));
  }
  function releaseSpaceMouse(text) {
    if (hidDevice) hidDevice.removeEventListener("inputreport", onReport);
    hidDevice = null;
    state.hid = [0, 0, 0, 0, 0, 0];
    $("spacemouse").textContent = text;
    sendInput();
  }
  async function connectSpaceMouse() {
    if (!navigator.hid) {
      $("spacemouse").textContent = "no WebHID in this browser (Chrome or Edge, on http://127.0.0.1 or https)";
      return;
    }
    try {
      const devices = await navigator.hid.requestDevice({ filters: SPACEMOUSE_FILTERS });
      if (!devices.length) { $("spacemouse").textContent = "no SpaceMouse chosen"; return; }
      const device = devices[0];
      if (!device.opened) await device.open();
      if (hidDevice && hidDevice !== device) releaseSpaceMouse("");
      hidDevice = device;
      device.addEventListener("inputreport", onReport);
      $("spacemouse").textContent = `SpaceMouse: ${device.productName || "3Dconnexion device"}`;
    } catch (error) {
      $("spacemouse").textContent = `SpaceMouse: ${error.message || error}`;
    }
  }
  $("spacemouse-connect").onclick = connectSpaceMouse;
  if (navigator.hid) {
    navigator.hid.addEventListener("disconnect", (event) => {
      if (event.device === hidDevice) releaseSpaceMouse("SpaceMouse disconnected: stopped");
    });
  }

  // Focus lost or page hidden: keys, jog buttons and the SpaceMouse let go (their releases
  // may never reach this page).
  function clearKeys() {
    if (state.held.size || Object.keys(state.jog).length || state.hid.some(Boolean)) {
      state.held.clear();
      state.jog = {};
      state.hid = [0, 0, 0, 0, 0, 0];
      sendInput();
    }
  }

  // A joint's − / + button, held: that joint alone at a share of its velocity limit (the
  // server's JOG_SHARE x speed); released, left or cancelled: it stops. The heartbeat carries
  // it, so the dead man applies as to the keys.
  function jogButton(name, sign) {
    const button = document.createElement("button");
    button.className = `jog ${sign > 0 ? "plus" : "minus"}`;
    button.textContent = sign > 0 ? "+" : "−";
    button.title = `jog ${name} ${sign > 0 ? "up" : "down"} (hold)`;
    const release = () => {
      if (state.jog[name] === sign) {
        delete state.jog[name];
        state.jogLog.push({ name, sign, down: false, at: performance.now() });
        button.classList.remove("on");
        sendInput();
      }
    };
    button.addEventListener("pointerdown", (event) => {
      if (event.button !== 0) return;
      state.jog[name] = sign;
      state.jogLog.push({ name, sign, down: true, at: performance.now() });
      button.classList.add("on");
      sendInput();
    });
    for (const type of ["pointerup", "pointerleave", "pointercancel"]) button.addEventListener(type, release);
    return button;
  }
  // Keys go to the robot whatever has the focus: the handlers run in the capture phase, before
  // any element sees the key, and a robot key's default action is prevented (a <select>'s
  // type-ahead, a slider's step). Other keys never change a form control either: the strategy
  // menus and the speed slider are set with the pointer (Tab still moves the focus); a text
  // field, if there is one, keeps its keys.
  const typing = (element) => Boolean(element) && (element.isContentEditable || element.tagName === "TEXTAREA" ||
    (element.tagName === "INPUT" && !["range", "checkbox", "radio", "button", "submit", "reset", "color"].includes(element.type)));
  const formControl = (element) => Boolean(element) && ["SELECT", "INPUT"].includes(element.tagName) && !typing(element);
  const robotKey = (code) => state.moveKeys.has(code) || code in ACTION_KEYS;
  const passes = (event) => ["Tab", "Shift", "Control", "Alt", "Meta"].includes(event.key) || event.ctrlKey || event.metaKey;

  window.addEventListener("keydown", (event) => {
    if (typing(event.target)) return;
    if (!robotKey(event.code)) {
      if (formControl(event.target) && !passes(event)) event.preventDefault();  // never a silent change
      return;
    }
    event.preventDefault();
    event.stopPropagation();
    if (formControl(document.activeElement)) document.activeElement.blur();
    if (state.moveKeys.has(event.code)) {
      if (!state.held.has(event.code)) {
        state.held.add(event.code);
        state.keyLog.push({ code: event.code, down: true, at: performance.now() });
        state.keySeq = state.seq + 1;
        state.keyTime = performance.now();
        sendInput();
      }
      return;
    }
    const action = ACTION_KEYS[event.code];
    if (action === "halt") act("halt");  // a held or repeated stop key stops again: harmless
    else if (event.repeat) return;
    else if (action === "record-toggle") act("record", { on: !state.recording });
    else act(action);
  }, true);
  window.addEventListener("keyup", (event) => {
    if (typing(event.target)) return;
    if (robotKey(event.code)) {
      event.preventDefault();
      event.stopPropagation();
    }
    if (state.held.delete(event.code)) {
      state.keyLog.push({ code: event.code, down: false, at: performance.now() });
      sendInput();
    }
  }, true);
  window.addEventListener("blur", clearKeys);
  document.addEventListener("visibilitychange", () => {
    if (document.hidden) clearKeys();
  });

  function act(type, extra = {}) { send({ type, ...extra }); }
  $("stop").onclick = () => act("halt");
  $("resume").onclick = () => act("resume");
  $("reverse").onclick = () => act("reverse");
  $("record").onclick = () => act("record", { on: !state.recording });
  $("home").onclick = () => act("home");
  $("claim").onclick = () => act("claim");
  for (const id of ["frame-hand", "frame-base"]) $(id).onclick = (e) => act("frame", { frame: e.target.dataset.frame });
  for (const id of ["mode-twist", "mode-uncoupled"]) $(id).onclick = (e) => act("mode", { mode: e.target.dataset.mode });
  // A control used gives the focus back, so that the next keys are the robot's.
  $("singularity").onchange = (e) => { act("configure", { singularity: e.target.value }); e.target.blur(); };
  $("wrist").onchange = (e) => { act("configure", { wrist: e.target.value }); e.target.blur(); };
  $("speed").onchange = (e) => e.target.blur();
  $("speed").oninput = (e) => {
    state.speed = Number(e.target.value) / 100;
    $("speed-value").textContent = `${e.target.value} %`;
    sendInput();
  };
  // Buttons keep no focus (those made later too), so Space never "clicks" the last one pressed.
  document.addEventListener("focusin", (e) => { if (e.target.tagName === "BUTTON") e.target.blur(); });

  // ---------------------------------------------------------------- what arrives
  function onHello(hello) {
    state.hello = hello;
    state.moveKeys = new Set(hello.keys);
    $("robot").textContent = `· ${hello.robot}`;
    $("rate").title = $("p99").title = `control loop: ${hello.scheduling}`;
    document.title = `pinrate teleop · ${hello.robot}`;
    for (const [id, names, chosen] of [["singularity", hello.singularities, hello.singularity],
                                       ["wrist", hello.wrists, hello.wrist]]) {
      $(id).replaceChildren(...names.map((name) => new Option(name, name, false, name === chosen)));
    }
    // The partition's joints, then the others (a gripper's fingers: held still, never "at a
    // limit" for sitting at one); each name whole (it wraps rather than being cut).
    $("joints").replaceChildren();
    $("joints-undriven").replaceChildren();
    const joggable = new Set(hello.joggable);
    hello.joints.forEach((joint, index) => {
      joint.jog = joggable.has(joint.name);
      const row = document.createElement("div");
      row.className = joint.driven ? "joint" : "joint undriven";
      row.id = `joint-${index}`;
      row.dataset.name = joint.name;
      const name = document.createElement("span");
      name.className = "name";
      name.title = `${joint.name} (${joint.unit}` + (joint.lower === null ? ", unlimited)" :
        `, ${format(joint.lower, 3)} to ${format(joint.upper, 3)})`);
      name.textContent = joint.name;
      const bar = document.createElement("div");
      bar.className = joint.lower === null ? "bar unlimited" : "bar";
      bar.innerHTML = '<div class="marker"></div>';
      const value = document.createElement("span");
      value.className = "value";
      const jog = joint.jog ? [jogButton(joint.name, -1), jogButton(joint.name, 1)] : [document.createElement("span"), document.createElement("span")];
      row.append(jog[0], name, bar, value, jog[1]);
      $(joint.driven ? "joints" : "joints-undriven").appendChild(row);
    });
    $("undriven").hidden = hello.joints.every((joint) => joint.driven);
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
    $("status").classList.toggle("deadman", Boolean(frame.dead_man));
    $("status-word").textContent = frame.status;
    $("status-detail").textContent = frame.detail;
    $("rho").textContent = format(frame.rho);
    $("conditioning").textContent = frame.conditioning ?
      `${format(frame.conditioning.value)} (${frame.conditioning.block})` : "–";
    $("rate").textContent = `${format(frame.loop.rate, 0)} Hz`;
    $("p99").textContent = `${format(frame.loop.p99_ms, 2)} ms`;
    $("stop").textContent = frame.halted ? "STOPPED" : "STOP";
    $("stop").classList.toggle("on", frame.halted);
    $("resume").disabled = !frame.halted;
    $("record").textContent = frame.recording ? "stop recording" : "record";
    $("record").classList.toggle("on", frame.recording);
    $("reverse").classList.toggle("on", frame.reversing);
    $("mode-twist").classList.toggle("chosen", frame.mode === "twist");
    $("mode-uncoupled").classList.toggle("chosen", frame.mode === "uncoupled");
    if (state.hello && frame.mode !== state.mode) {
      state.mode = frame.mode;
      const wrist = state.hello.wrist_joints;
      const pairs = ["I / K", "J / L", "O / U"].slice(0, wrist.length).map((keys, i) => `${keys}: ${wrist[i]} ±`);
      $("mode-help").textContent = "Uncoupled: W/S A/D E/Q move the wrist centre (arm joints only); " + pairs.join(", ") + ".";
      $("mode-help").hidden = frame.mode !== "uncoupled";
    }
    $("frame-hand").classList.toggle("chosen", frame.frame === "hand");
    $("frame-base").classList.toggle("chosen", frame.frame === "base");
    if ($("singularity").value !== frame.singularity) $("singularity").value = frame.singularity;
    if ($("wrist").value !== frame.wrist) $("wrist").value = frame.wrist;
    if (frame.tip) {  // the tip's pose in the world: m, rad (and degrees)
      $("tcp-name").textContent = frame.tip.name;
      ["x", "y", "z"].forEach((axis, i) => { $(`tcp-${axis}`).textContent = format(frame.tip.position[i], 6); });
      ["roll", "pitch", "yaw"].forEach((angle, i) => {
        $(`tcp-${angle}`).textContent = format(frame.tip.rpy[i], 6);
        $(`tcp-${angle}-deg`).textContent = format(frame.tip.rpy[i] * 180 / Math.PI, 3);
      });
    }
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
        const gauged = joint.driven && joint.lower !== null;  // a joint not driven is at no limit it could hit
        row.classList.toggle("near", gauged && (share < 0.03 || share > 0.97));
        row.classList.toggle("limit", gauged && (share <= 1e-6 || share >= 1 - 1e-6));
        row.classList.toggle("held", frozen.has(joint.name));
      });
    }
  }
})();
