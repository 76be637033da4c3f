// Live mode's connection: the WebSocket /ws of stride-viz, reopened with a growing delay (0.5 s
// doubling to 10 s, back to 0.5 s once a connection opens) whenever it closes.

const FIRST_DELAY_MS = 500;
const MAX_DELAY_MS = 10000;

export function wsUrl(path) {
  const url = new URL(path, window.location.href);
  url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
  return url.href;
}

/**
 * Opens `url` and keeps it open. `onFrame` gets each frame (a message may hold one JSON frame or
 * an array of them), `onState` the connection's state: 'open', or 'closed' with the delay [ms]
 * before the next attempt.
 */
export function connect(url, { onFrame, onState }) {
  let delay = FIRST_DELAY_MS;
  const open = () => {
    const ws = new WebSocket(url);
    ws.onopen = () => {
      delay = FIRST_DELAY_MS;
      onState('open');
    };
    ws.onmessage = (event) => {
      if (typeof event.data !== 'string') return;
      let msg;
      try {
        msg = JSON.parse(event.data);
      } catch {
        console.warn('stride-viz: a message that is not JSON, ignored');
        return;
      }
      for (const frame of Array.isArray(msg) ? msg : [msg]) onFrame(frame);
    };
    ws.onclose = () => {
      onState('closed', delay);
      setTimeout(open, delay);
      delay = Math.min(2 * delay, MAX_DELAY_MS);
    };
  };
  open();
}
