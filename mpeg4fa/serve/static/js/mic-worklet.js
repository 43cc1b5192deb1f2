// The microphone's audio at 16 kHz, s16le, in 20 ms chunks (mpeg4fa/serve/microphone.py): an AudioWorklet
// that low-passes the context's rate (a 63-tap windowed-sinc FIR at 7 kHz, Blackman window) and
// resamples by linear interpolation, its position running on from one 128-sample block to the next, so
// the stream has no seams. Each full chunk goes to the page as an Int16Array (transferred).
const TARGET = 16000, CHUNK = 320, TAPS = 63, CUTOFF = 7000;

class MicPcm16k extends AudioWorkletProcessor {
  constructor() {
    super();
    this.ratio = sampleRate / TARGET;
    this.filter = sampleRate > TARGET ? lowpass(CUTOFF / sampleRate) : null;
    this.history = new Float32Array(TAPS);  // the last TAPS input samples, a ring
    this.at = 0;                              // ring position
    this.index = -1;                          // index of the last filtered sample
    this.prev = 0; this.last = 0;             // filtered samples index-1 and index
    this.next = 0;                            // input index of the next output sample
    this.out = new Int16Array(CHUNK); this.filled = 0;
  }

  process(inputs) {
    const input = inputs[0];
    if (!input || !input.length) return true;
    const n = input[0].length, channels = input.length;
    for (let i = 0; i < n; i++) {
      let x = 0;
      for (let c = 0; c < channels; c++) x += input[c][i];
      x /= channels;
      this.push(this.filter ? this.fir(x) : x);
    }
    return true;
  }

  fir(x) {
    const h = this.history, f = this.filter;
    h[this.at] = x;
    let y = 0, k = this.at;
    for (let j = 0; j < TAPS; j++) { y += f[j] * h[k]; k = k === 0 ? TAPS - 1 : k - 1; }
    this.at = (this.at + 1) % TAPS;
    return y;
  }

  push(y) {
    this.prev = this.last; this.last = y; this.index++;
    while (this.next <= this.index) {
      const frac = this.next - (this.index - 1);
      const v = this.index === 0 ? y : this.prev + frac * (this.last - this.prev);
      this.out[this.filled++] = Math.max(-32768, Math.min(32767, Math.round(v * 32768)));
      this.next += this.ratio;
      if (this.filled === CHUNK) {
        this.port.postMessage(this.out, [this.out.buffer]);
        this.out = new Int16Array(CHUNK); this.filled = 0;
      }
    }
  }
}

function lowpass(fc) {  // fc: cutoff over the sample rate
  const h = new Float32Array(TAPS), m = (TAPS - 1) / 2;
  let sum = 0;
  for (let i = 0; i < TAPS; i++) {
    const k = i - m;
    const sinc = k === 0 ? 2 * fc : Math.sin(2 * Math.PI * fc * k) / (Math.PI * k);
    const w = 0.42 - 0.5 * Math.cos(2 * Math.PI * i / (TAPS - 1)) + 0.08 * Math.cos(4 * Math.PI * i / (TAPS - 1));
    h[i] = sinc * w; sum += h[i];
  }
  for (let i = 0; i < TAPS; i++) h[i] /= sum;
  return h;
}

registerProcessor("mic-pcm16k", MicPcm16k);
