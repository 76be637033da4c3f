// Starts stride-viz (scripts and tests: browser_test.mjs, tools/paper/snapshots.mjs) and resolves
// the address from its start line, `stride-viz: http://HOST:PORT/ (...)` (viz/README.md).
//   startViz(bin, args) -> { child, url: Promise<string>, stderr: () => string }
import { spawn } from 'node:child_process';

const START_TIMEOUT_MS = 60000; // stride-viz reads the whole log before it listens

export function startViz(bin, args) {
  const child = spawn(bin, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  child.stderr.on('data', (d) => { stderr += d; });
  const url = new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`stride-viz printed no address in ${START_TIMEOUT_MS / 1000} s; stderr:\n${stderr}`)), START_TIMEOUT_MS);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/^stride-viz: (http:\/\/[^\s/]+\/)/m);
      if (m) {
        clearTimeout(timer);
        resolve(m[1]);
      }
    });
    child.on('exit', (code, signal) => {
      clearTimeout(timer);
      reject(new Error(`stride-viz exited (${code ?? signal}) before it listened; stderr:\n${stderr}`));
    });
  });
  return { child, url, stderr: () => stderr };
}
