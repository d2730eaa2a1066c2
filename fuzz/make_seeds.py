"""Writes the seed corpora of the parser targets (seeds/merl_decode,
seeds/material_toml, seeds/capi_toml, seeds/query_csv; table_loader's are
hand-made, see harness.rs). Run from fuzz/ with the package installed:
``python make_seeds.py``. The material files are what the package writes
(``Material.to_toml``) and what the docs show, valid and not."""

import pathlib
import struct

import twoscale

HERE = pathlib.Path(__file__).resolve().parent


def write(target, name, data):
    d = HERE / "seeds" / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())


# merl_decode: flags, two directions (six f64), 12-byte patches (u32 position, 8 bytes XORed).
def merl(flags, i, o, patches=()):
    out = bytes([flags]) + struct.pack("<6d", *i, *o)
    for position, value in patches:
        out += struct.pack("<I", position) + struct.pack("<d", value)
    return out


up, out_ = (0.3, 0.1, 0.95), (-0.3, 0.0, 0.95)
write("merl_decode", "plain", merl(0, up, out_, [(5, 12.5), (1_458_000 + 5, 3.0)]))
write("merl_decode", "missing", merl(0, up, out_, [(7, -1.0), (8, float("inf"))]))
write("merl_decode", "subnormal", merl(0, up, out_, [(9, 5e-324), (2 * 1_458_000, 1e300)]))
write("merl_decode", "nan-direction", merl(0, (float("nan"), 0.0, 1.0), (0.0, 0.0, 0.0)))
write("merl_decode", "below", merl(0, (0.3, 0.0, -0.9), (1e308, -1e308, 1e-308)))
write("merl_decode", "header", merl(1, up, out_) + struct.pack("<I", 0) + struct.pack("<2i", 90 ^ 180, 0))
write("merl_decode", "truncated", merl(2 | (15 << 4), up, out_))

# Material files.
texts = {
    "fit": "[material]\nbeta = 0.0598\np = 1.0\neta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]\n"
           "sigma_s = 0.0273\nb = 4.8418\nc = 2.0\nlambertian = 8.85e-07\n\n[metrics]\nrmse = [0.01, 0.01, 0.01]\n",
    "spectrum": "[material]\nbeta = 0.1\np = 1.5\neta = { lambda = [0.4, 0.5, 0.6], n = [0.2, 0.3, 0.4], k = [3.0, 3.1, 3.2] }\n",
    "plastic": "[material]\nbeta = 0.2\np = 2.0\neta = [[1.5, 0.0], [1.5, 0.0], [1.5, 0.0]]\nbase = \"plastic\"\n"
               "albedo = 0.8\nmasking = \"height-correlated\"\nmultiple_scattering = \"kulla-conty\"\n"
               "rgb_mode = \"integrated\"\n",
    "refused": "[material]\nbeta = 20\np = 9\neta = [[1, 0]]\n",
    "syntax": "[material\nbeta = = 1\n",
    "unknown-key": "[material]\nbeta = 0.1\np = 1.0\neta = [[1, 0], [1, 0], [1, 0]]\nshine = 3\n",
}
texts["preset-gold"] = twoscale.Material.preset("gold-rough", colour="white").to_toml()
texts["preset-marble"] = twoscale.Material.preset("marble").with_layer(albedo=0.3).to_toml()
for name, text in texts.items():
    write("material_toml", name, text)
    write("capi_toml", name, text)

# query_csv: byte 0 = quantity (low 3 bits: g1, sigma-ratio, fresnel, conv, brdf),
# bit 3 --clamp, bits 4-5 the brdf material (none, pairs, spectrum).
rows = {
    "g1": (0, "p,a\n1,0.5\n0.2,0.1\n7,1\n"),
    "g1-clamp": (8, "p,a\n0.1,-3\nnan,1\n"),
    "sigma-ratio": (1, "theta_i,B,c\n0.3,4,2\n1.6,0.5,1.2\n"),
    "fresnel": (2, "n,k,cos_theta\n0.2,3.5,0.9\n-1,0,0.5\n"),
    "conv": (3, "u,c,beta,p,theta_h\n0.5,2,0.1,1,0.2\n"),
    "brdf": (4, "beta,p,sigma_s,b,c,n,k,lambda,ix,iy,iz,ox,oy,oz\n"
                "0.1,1,0.02,3,2,0.2,3.5,0.55,0.3,0,0.95,-0.3,0,0.95\n"),
    "brdf-material": (4 | 16, "channel,ix,iy,iz,ox,oy,oz\n0,0.3,0,0.95,-0.3,0,0.95\n3,0,0,1,0,0,1\n"),
    "brdf-spectral": (4 | 32, "lambda,ix,iy,iz,ox,oy,oz\n0.55,0.3,0,0.95,-0.3,0,0.95\n0.2,0,0,1,0,0,1\n"),
    "fields": (0, "p,a,extra\n1,0.5\n,,\n1,x,2\n"),
    "missing-column": (3, "u,c,beta\n0.5,2,0.1\n"),
    "empty": (1, "\n  \n"),
}
for name, (selector, text) in rows.items():
    write("query_csv", name, bytes([selector]) + text.encode())
write("query_csv", "not-utf8", bytes([0]) + b"p,a\n1,\xff0.5\n")
