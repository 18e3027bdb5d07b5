"""What the colour camera sees of a scenario: the person's skin tone, the box's print, the table's
surface, the far wall and the lighting.

Every colour is linear RGB with the sRGB primaries and D65 white (the renderer's working space),
albedos in [0, 1]; radiance is in units where a white (albedo 1) surface lit frontally by a light
of intensity 1 has radiance 1 in each channel of that light's normalised colour.

**Skin** (per person, the same in every scenario of that user): a tone of the Monk Skin Tone scale
(Monk 2019; Google's "Monk Skin Tone Scale", skintone.google), its ten swatches in sRGB
(:data:`MONK_SRGB`): MST1 f6ede4, MST2 f3e7db, MST3 f7ead0, MST4 eadaba, MST5 d7bd96, MST6 a07e56,
MST7 825c43, MST8 604134, MST9 3a312a, MST10 292420 (as published by Google; not re-measured
here). The tone index is drawn uniformly over the ten from a generator seeded with the user index
(``SeedSequence([user, *b"skin-tone"])``): a stated choice, equal representation of every tone, as
skin-tone fairness evaluations use; the world's prevalence of the tones is not uniform. Within a
tone the albedo is jittered: a common lightness factor 1 + 0.04 N(0, 1) and a per-channel factor
1 + 0.015 N(0, 1) (:data:`SKIN_LIGHTNESS_JITTER`, :data:`SKIN_CHANNEL_JITTER`: smaller than the
steps between neighbouring swatches, so the tone stays recognisable), clipped to [0, 1]. The
swatches are skin as it looks in a photograph, not how much light it reflects: taken as albedo,
MST1's red channel (0.92 linear) would make a light hand brighter than a white-coated box. Diffuse
reflectance spectra of skin put the lightest skin at about 0.6 in the red (Anderson & Parrish 1981,
"The optics of human skin", J. Invest. Dermatol. 77(1)), so every swatch's linear RGB is scaled by
:data:`SKIN_REFLECTANCE_SCALE` = 0.6 / 0.92: each tone keeps its chromaticity and the tones their
ratios, and the lightest reflects 0.6 in the red.

**Box** (per scenario, the "appearance" stream): a printed cardboard box. Its board is kraft
(sRGB c19a6b) or white-coated (sRGB e9e4da) with probability 1/2, its lightness jittered by
1 + 0.05 N(0, 1); each face (+x, -x, +y, -y, +z, -z, in the box's frame) carries ink of one
colour (a subtractive ink on the board: the board's albedo times a factor per channel uniform in
[0.05, 0.6], :data:`INK_FACTOR`) in
square cells of 4-12 mm of which a fraction 0.1-0.4 is inked (a hashed pattern, like printed
text and logos), and a stripe across the face (along either face axis, its centre within 0.6 of
the half size from the middle and its half width 0.05-0.2 of the face's size).

**Table** (per scenario): a wood or laminate top, base colour between sRGB d9b98c (light) and
8a623e (dark), grain colour the base times 0.6-0.85, in world xy: value noise (integer hashes,
bilinear) stretched along a drawn grain direction, 4-15 cm along and 3-8 mm across the grain,
with an octave twice as fine (0.35 of the weight). Textures are point-sampled at the pixel's ray
(no filtering): the finest scales are chosen at or above a pixel at the box's distance (1 mm is
about 1 px of the 640 x 480 colour camera at 0.55 m); farther away they alias.

**Far wall**: a constant radiance (the background where the rays hit nothing), a painted wall's
grey 0.15-0.45 (linear) with a tint of +-5 % per channel.

**Lighting** (indoor lab, ceiling fixtures): ambient plus one or two directional lights (a second
with probability 1/2). The key light comes from elevation 50-85 degrees above the horizon and any
azimuth, intensity 0.45-0.75; the fill from elevation 20-60 degrees, intensity 0.1-0.3; colour
temperatures 3000-6500 K (warm-white to daylight LED and fluorescent lamps), converted to linear
RGB by the Planckian locus of Kim et al. (2002, "Design of advanced color temperature control
system for HDTV applications", J. Korean Phys. Soc. 41(6)): a cubic in 1/T
for chromaticity x, a cubic in x for y, then XYZ (Y = 1) to linear sRGB (IEC 61966-2-1's matrix).
The ambient is 0.15-0.3 times the key light's colour (the room's inter-reflected light). The
lights' parameters are always drawn, two lights' worth, whether or not the second is used.

The parameters are computed in Python's scalar ``math`` (libm; only for the few parameters, never
per pixel), the textures evaluated per pixel in :mod:`benchmark.camera.colour_kernels` with
integer hashes and ``+ - * /`` only.

Ablations: :meth:`Appearance.ablated` fixes the skin tone, switches the box's print or the table's
texture off (uniform albedo per label) or fixes the lighting (:data:`FIXED_LIGHTING`);
:meth:`Appearance.plain` switches both textures off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from benchmark.errors import BenchmarkError

MONK_SRGB = ("f6ede4", "f3e7db", "f7ead0", "eadaba", "d7bd96", "a07e56", "825c43", "604134", "3a312a", "292420")
"""The Monk Skin Tone scale's ten swatches, MST1 (lightest) to MST10, sRGB hex (Monk 2019, Google)."""
SKIN_REFLECTANCE_SCALE = 0.6 / 0.92
"""Linear RGB albedo per unit of a Monk swatch's linear RGB: MST1's red channel (0.92) becomes the
lightest skin's measured red reflectance, about 0.6 (Anderson & Parrish 1981)."""
SKIN_LIGHTNESS_JITTER = 0.04
"""Standard deviation of a person's common lightness factor around the tone's swatch."""
SKIN_CHANNEL_JITTER = 0.015
"""Standard deviation of a person's per-channel factor around the tone's swatch."""
KELVIN = (3000.0, 6500.0)
"""Range of the lights' colour temperatures, [K]."""
KEY_ELEVATION_DEG = (50.0, 85.0)
FILL_ELEVATION_DEG = (20.0, 60.0)
KEY_INTENSITY = (0.45, 0.75)
FILL_INTENSITY = (0.1, 0.3)
AMBIENT = (0.15, 0.3)
INK_FACTOR = (0.05, 0.6)
"""Range of the ink's per-channel factor on the board's albedo."""
BOX_CELL_M = (0.004, 0.012)
BOX_INK_FRACTION = (0.1, 0.4)
TABLE_ALONG_M = (0.04, 0.15)
TABLE_ACROSS_M = (0.003, 0.008)

_KRAFT, _WHITE_BOARD = "c19a6b", "e9e4da"
_TABLE_LIGHT, _TABLE_DARK = "d9b98c", "8a623e"
_XYZ_TO_SRGB = ((3.2404542, -1.5371385, -0.4985314), (-0.9692660, 1.8760108, 0.0415560),
                (0.0556434, -0.2040259, 1.0572252))


def srgb_to_linear(code: float) -> float:
    """The linear value of an sRGB-encoded value in [0, 1] (IEC 61966-2-1)."""
    return code / 12.92 if code <= 0.04045 else ((code + 0.055) / 1.055) ** 2.4


def hex_to_linear(hex_rgb: str) -> np.ndarray:
    """Linear RGB (3,) of an sRGB hex colour like ``"f6ede4"``."""
    return np.array([srgb_to_linear(int(hex_rgb[i : i + 2], 16) / 255.0) for i in (0, 2, 4)])


def kelvin_to_rgb(kelvin: float) -> np.ndarray:
    """Linear sRGB (3,) of a black body at ``kelvin`` (1667-25000 K), luminance Y = 1 (Kim et al. 2002)."""
    T = float(kelvin)
    if not 1667.0 <= T <= 25000.0:
        raise BenchmarkError(f"colour temperature must be in [1667, 25000] K, got {kelvin!r}")
    a, b, c = 1e9 / T**3, 1e6 / T**2, 1e3 / T
    if T <= 4000.0:
        x = -0.2661239 * a - 0.2343589 * b + 0.8776956 * c + 0.179910
    else:
        x = -3.0258469 * a + 2.1070379 * b + 0.2226347 * c + 0.240390
    if T <= 2222.0:
        y = -1.1063814 * x**3 - 1.34811020 * x**2 + 2.18555832 * x - 0.20219683
    elif T <= 4000.0:
        y = -0.9549476 * x**3 - 1.37418593 * x**2 + 2.09137015 * x - 0.16748867
    else:
        y = 3.0817580 * x**3 - 5.87338670 * x**2 + 3.75112997 * x - 0.37001483
    X, Y, Z = x / y, 1.0, (1.0 - x - y) / y
    return np.array([m[0] * X + m[1] * Y + m[2] * Z for m in _XYZ_TO_SRGB])


def _direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """The unit direction a light at (elevation, azimuth) travels, world frame (downwards)."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return -np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])


@dataclass(frozen=True)
class Lighting:
    """Ambient and directional lights (world frame).

    Attributes:
        ambient: Ambient irradiance, linear RGB (3,).
        direction: Unit direction each light travels, (L, 3), L in {1, 2}.
        rgb: Each light's linear RGB (intensity times its colour), (L, 3).
        kelvin: Each light's colour temperature, (L,) [K].
    """

    ambient: np.ndarray
    direction: np.ndarray
    rgb: np.ndarray
    kelvin: np.ndarray

    def white(self) -> np.ndarray:
        """Linear RGB of a white surface lit frontally by every light at once (what an automatic
        white balance neutralises), (3,)."""
        return self.ambient + self.rgb.sum(axis=0)


FIXED_LIGHTING = Lighting(ambient=0.22 * kelvin_to_rgb(4500.0), direction=_direction(65.0, 60.0)[None, :],
                          rgb=0.6 * kelvin_to_rgb(4500.0)[None, :], kelvin=np.array([4500.0]))
"""The lighting of the "lighting fixed" ablation: one 4500 K key light at elevation 65, azimuth
60 degrees (above, a little behind the camera's side), intensity 0.6, ambient 0.22."""


@dataclass(frozen=True)
class Appearance:
    """What the colour camera sees (module docstring for the draws and their ranges).

    Attributes:
        skin_tone: The person's Monk Skin Tone index, 1..10.
        skin_albedo: The skin's albedo, linear RGB (3,).
        box_base: The board's albedo per face (+x, -x, +y, -y, +z, -z), (6, 3).
        box_ink: The ink's albedo per face, (6, 3).
        box_par: Per face: cell size [m], inked fraction, stripe axis (0: along the face's first
            axis, 1: its second), stripe start and end (normalised face coordinate, [-1, 1]),
            hash seed, (6, 6).
        table_base: The table's base albedo, (3,).
        table_grain: The grain's albedo, (3,).
        table_par: Grain direction in world xy (unit, 2), scale along and across the grain [m],
            hash seed, (5,).
        background: Radiance where nothing is seen (the far wall), linear RGB (3,).
        lighting: The :class:`Lighting`.
        box_print: False: the box has the uniform albedo ``box_base[0]`` (its print off).
        table_texture: False: the table has the uniform albedo ``table_base``.
    """

    skin_tone: int
    skin_albedo: np.ndarray
    box_base: np.ndarray
    box_ink: np.ndarray
    box_par: np.ndarray
    table_base: np.ndarray
    table_grain: np.ndarray
    table_par: np.ndarray
    background: np.ndarray
    lighting: Lighting
    box_print: bool = True
    table_texture: bool = True

    def __post_init__(self):
        if isinstance(self.skin_tone, bool) or not isinstance(self.skin_tone, (int, np.integer)) \
                or not 1 <= self.skin_tone <= len(MONK_SRGB):
            raise BenchmarkError(f"skin_tone must be a Monk Skin Tone index 1..{len(MONK_SRGB)}, got {self.skin_tone!r}")
        for name, shape in (("skin_albedo", (3,)), ("box_base", (6, 3)), ("box_ink", (6, 3)), ("box_par", (6, 6)),
                            ("table_base", (3,)), ("table_grain", (3,)), ("table_par", (5,)), ("background", (3,))):
            v = np.ascontiguousarray(getattr(self, name), dtype=np.float64)
            if v.shape != shape or not np.all(np.isfinite(v)):
                raise BenchmarkError(f"Appearance.{name} must be finite with shape {shape}, got {v.shape}")
            object.__setattr__(self, name, v)

    @property
    def box_albedo(self) -> np.ndarray:
        """The box's albedo with its print off, (3,)."""
        return self.box_base[0]

    def plain(self) -> "Appearance":
        """The same appearance with uniform albedo per label (box print and table texture off)."""
        return replace(self, box_print=False, table_texture=False)

    def ablated(self, *, skin_tone: int | None = None, box_print: bool = True, table_texture: bool = True,
                fixed_lighting: bool = False) -> "Appearance":
        """An ablation: each source of appearance switched off on its own.

        Args:
            skin_tone: Give the person this Monk tone's swatch, unjittered (None: keep theirs).
            box_print: False switches the box's print off.
            table_texture: False switches the table's texture off.
            fixed_lighting: True replaces the drawn lighting by :data:`FIXED_LIGHTING`.
        """
        out = self
        if skin_tone is not None:
            if isinstance(skin_tone, bool) or not isinstance(skin_tone, (int, np.integer)) \
                    or not 1 <= skin_tone <= len(MONK_SRGB):
                raise BenchmarkError(f"skin_tone must be None or a Monk index 1..{len(MONK_SRGB)}, got {skin_tone!r}")
            out = replace(out, skin_tone=int(skin_tone), skin_albedo=hex_to_linear(MONK_SRGB[int(skin_tone) - 1]))
        out = replace(out, box_print=self.box_print and bool(box_print),
                      table_texture=self.table_texture and bool(table_texture))
        if fixed_lighting:
            out = replace(out, lighting=FIXED_LIGHTING)
        return out


def skin_of(user: int) -> tuple[int, np.ndarray]:
    """The person's Monk tone index (1..10) and skin albedo (linear RGB (3,)), drawn from the user index.

    Draws, in order: the tone index (uniform over the ten), the common lightness normal, then one
    normal per channel.
    """
    rng = np.random.default_rng(np.random.SeedSequence([int(user), *b"skin-tone"]))
    tone = int(rng.integers(1, len(MONK_SRGB) + 1))
    common = 1.0 + SKIN_LIGHTNESS_JITTER * float(rng.standard_normal())
    channel = 1.0 + SKIN_CHANNEL_JITTER * rng.standard_normal(3)
    albedo = np.clip(hex_to_linear(MONK_SRGB[tone - 1]) * SKIN_REFLECTANCE_SCALE * common * channel, 0.0, 1.0)
    return tone, albedo


def people_with_tone(tone: int, count: int = 1, start: int = 0) -> list[int]:
    """The first ``count`` user indices from ``start`` up whose drawn Monk tone is ``tone`` (for
    pictures and ablations across skin tones).

    Raises:
        BenchmarkError: For a tone outside 1..10, count < 1 or start < 0.
    """
    if isinstance(tone, bool) or not isinstance(tone, (int, np.integer)) or not 1 <= tone <= len(MONK_SRGB):
        raise BenchmarkError(f"tone must be a Monk Skin Tone index 1..{len(MONK_SRGB)}, got {tone!r}")
    if int(count) < 1 or int(start) < 0:
        raise BenchmarkError(f"count must be >= 1 and start >= 0, got {count!r}, {start!r}")
    found, user = [], int(start)
    while len(found) < int(count):
        if skin_of(user)[0] == tone:
            found.append(user)
        user += 1
    return found


def appearance_of(scenario) -> Appearance:
    """The appearance of a scenario (:class:`benchmark.world.scenario.Scenario`): the skin from its
    user, the rest from its "appearance" stream.

    Draw order of the stream: the board (material uniform, lightness normal); per face in order
    +x, -x, +y, -y, +z, -z: ink factor (3 uniforms), cell size, inked fraction, stripe axis (integer),
    stripe centre, stripe half width, hash seed (integer); the table: base mix, grain darkness,
    grain angle, scale along, scale across, seed; the wall: grey, tint (3 uniforms); the lights:
    whether there are two, key (elevation, azimuth, kelvin, intensity), ambient level, fill
    (elevation, azimuth, kelvin, intensity).
    """
    tone, skin = skin_of(scenario.user)
    rng = scenario.rng("appearance")
    board = hex_to_linear(_KRAFT if rng.random() < 0.5 else _WHITE_BOARD)
    board = np.clip(board * (1.0 + 0.05 * float(rng.standard_normal())), 0.0, 1.0)
    ink, par = np.empty((6, 3)), np.empty((6, 6))
    for f in range(6):
        ink[f] = board * rng.uniform(*INK_FACTOR, 3)
        cell = float(rng.uniform(*BOX_CELL_M))
        frac = float(rng.uniform(*BOX_INK_FRACTION))
        axis = float(rng.integers(0, 2))
        centre = float(rng.uniform(-0.6, 0.6))
        half = float(rng.uniform(0.05, 0.2)) * 2.0  # of the face's size: normalised coordinates span 2
        seed = float(rng.integers(0, 1 << 24))
        par[f] = (cell, frac, axis, centre - half, centre + half, seed)
    mix = float(rng.uniform())
    light, dark = hex_to_linear(_TABLE_LIGHT), hex_to_linear(_TABLE_DARK)
    table_base = light + mix * (dark - light)
    table_grain = table_base * float(rng.uniform(0.6, 0.85))
    angle = float(rng.uniform(0.0, math.pi))
    along, across = float(rng.uniform(*TABLE_ALONG_M)), float(rng.uniform(*TABLE_ACROSS_M))
    table_par = np.array([math.cos(angle), math.sin(angle), along, across, float(rng.integers(0, 1 << 24))])
    background = float(rng.uniform(0.15, 0.45)) * (1.0 + rng.uniform(-0.05, 0.05, 3))
    two = bool(rng.random() < 0.5)
    key = (float(rng.uniform(*KEY_ELEVATION_DEG)), float(rng.uniform(0.0, 360.0)), float(rng.uniform(*KELVIN)),
           float(rng.uniform(*KEY_INTENSITY)))
    ambient_level = float(rng.uniform(*AMBIENT))
    fill = (float(rng.uniform(*FILL_ELEVATION_DEG)), float(rng.uniform(0.0, 360.0)), float(rng.uniform(*KELVIN)),
            float(rng.uniform(*FILL_INTENSITY)))
    lights = [key, fill] if two else [key]
    lighting = Lighting(
        ambient=ambient_level * kelvin_to_rgb(key[2]),
        direction=np.array([_direction(e, a) for e, a, _, _ in lights]),
        rgb=np.array([i * kelvin_to_rgb(k) for _, _, k, i in lights]),
        kelvin=np.array([k for _, _, k, _ in lights]),
    )
    return Appearance(skin_tone=tone, skin_albedo=skin, box_base=np.tile(board, (6, 1)), box_ink=ink, box_par=par,
                      table_base=table_base, table_grain=table_grain, table_par=table_par, background=background,
                      lighting=lighting)
