"""Make tests/speech/data/golden_text_frames.npz: made first from the pre-streaming encoder; remade when the
spec/ profiles change (issue 29 retuned them: the streaming encoder with the old profiles was first checked to
give the old golden to the bit)."""
import hashlib, json, numpy as np
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.fba import encode
TEXTS = {
 "tags": "(joy, 40, 0.5) Hello there, how are you today? (sadness, 30, 1) I am fine. Thank you very much. "
         "It was a long day (anger, 20, 2) and the bus was late. (neutral, 0, 0.3) Tomorrow is another day!",
 "mixed": "(surprise, 50, 0.4) 你好，世界！ Hello again. (joy, 63, 1) 我很高兴。 Bye now.",
}
CASES = [("tags", "low", True, 25.0), ("tags", "high", False, 25.0), ("tags", "both", True, 30.0),
         ("mixed", "high", True, 25.0), ("mixed", "low", False, 12.5)]
out, meta = {}, {}
for text, level, idle, fps in CASES:
    key = f"{text}-{level}-{int(idle)}-{fps:g}"
    e = encode_text(TEXTS[text], engine="estimate", level=level, idle=idle, fps=fps, seed=7)
    e2 = encode_text(TEXTS[text], engine="estimate", level=level, idle=idle, fps=fps, seed=7)
    data = encode(e.stream, e.coding())
    assert data == encode(e2.stream, e2.coding())
    out[key + ".values"] = e.values.astype(np.int32)
    out[key + ".fap_mask"] = e.stream.fap_mask
    out[key + ".fap_values"] = e.stream.fap_values
    out[key + ".viseme"] = e.stream.viseme
    out[key + ".expression"] = e.stream.expression
    meta[key] = {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data), "mask_types": list(e.mask_types),
                 "frames": len(e.stream)}
np.savez_compressed("tests/speech/data/golden_text_frames.npz", **out)
json.dump({"texts": TEXTS, "cases": CASES, "meta": meta}, open("tests/speech/data/golden_text_frames.json", "w"), indent=1, ensure_ascii=False)
print(meta)
