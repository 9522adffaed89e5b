// pinrate teleop console: the page's one WebSocket, in a dedicated Worker (design.md §3).
//
// The page's main thread can be blocked for most of a second per frame (software WebGL, a
// slow machine), so the heartbeat cannot live there: this worker sends the page's latest
// input every HEARTBEAT_MS whatever the main thread does, and each message carries
//   sent:  this worker's performance.now() (ms): the server ages the command from it
//          (its dead man, the Teleop's timeout, applies to these messages);
//   alive: when the main thread last spoke to this worker, on the same clock (ms): the
//          server zeroes the command once the main thread is silent for longer than its
//          freeze limit (a frozen page: the held keys may no longer be the operator's).
// A slow page so keeps the robot moving as commanded, a frozen one stops it within the
// freeze limit plus one heartbeat.
//
// Messages from the main thread: {type: "connect", url}, {type: "input", input} (the held
// input: the heartbeat's payload from now on, sent at once), {type: "send", message} (an
// action), {type: "alive"} (liveness only). Every one of them is a sign of life.
// To the main thread: {kind: "open"}, {kind: "closed"}, {kind: "binary", data} (meshcat's
// scene commands, in order), {kind: "message", message} (hello, role, event, frame). Frames
// are coalesced: while the main thread has not spoken since the last frame was handed to
// it, only the newest is kept (with the newest poses), so a slow page never piles them up.
"use strict";

const HEARTBEAT_MS = 50;
let socket = null;
let input = null; // the main thread's latest input message, without its stamps
let controlling = false;
let mainAt = performance.now(); // when the main thread last spoke (this worker's clock, ms)
let frameHandedAt = -Infinity; // when the last frame went to the main thread
let pending = null; // a frame held back for a main thread still busy with the last one

function send(message) {
  if (socket && socket.readyState === 1) {
    socket.send(JSON.stringify({ ...message, sent: performance.now(), alive: mainAt }));
  }
}

function heartbeat() {
  if (controlling && input) send(input);
}

function handFrame(frame) {
  if (mainAt >= frameHandedAt) {
    frameHandedAt = performance.now();
    postMessage({ kind: "message", message: frame });
    return;
  }
  if (pending && pending.poses && !frame.poses) frame = { ...frame, poses: pending.poses };
  pending = frame;
}

function connect(url) {
  socket = new WebSocket(url);
  socket.binaryType = "arraybuffer";
  socket.onopen = () => postMessage({ kind: "open" });
  socket.onclose = () => {
    controlling = false;
    postMessage({ kind: "closed" });
  };
  socket.onmessage = (event) => {
    if (typeof event.data !== "string") {
      postMessage({ kind: "binary", data: event.data }, [event.data]);
      return;
    }
    const message = JSON.parse(event.data);
    if (message.type === "role") {
      controlling = Boolean(message.controlling);
      if (controlling) heartbeat();
    }
    if (message.type === "frame") handFrame(message);
    else postMessage({ kind: "message", message });
  };
}

onmessage = (event) => {
  mainAt = performance.now();
  const data = event.data;
  if (pending) {
    const frame = pending;
    pending = null;
    frameHandedAt = mainAt;
    postMessage({ kind: "message", message: frame });
  }
  if (data.type === "connect") connect(data.url);
  else if (data.type === "input") {
    input = data.input;
    heartbeat();
  } else if (data.type === "send") send(data.message);
};

setInterval(heartbeat, HEARTBEAT_MS);
