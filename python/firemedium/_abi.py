"""The plugin's C ABI 1.3 (plugin/abi/include/firemedium.h) as ctypes declarations.

Kept to the header line by line: every struct begins with ``struct_size`` (set here to the size ctypes computes,
which the plugin checks), arrays of FmParam/FmRay/FmExit/FmScatter have the major version's layout.
"""

from __future__ import annotations

import ctypes as C

ABI_MAJOR = 1
ABI_MINOR = 4
ENTRY_SYMBOL = "firemedium_plugin_entry"

OK, INVALID_ARGUMENT, INVALID_PARAMETER, DATASET, UNSUPPORTED, PANIC = range(6)
STATUS_NAMES = {
    OK: "ok",
    INVALID_ARGUMENT: "invalid argument",
    INVALID_PARAMETER: "invalid parameter",
    DATASET: "dataset",
    UNSUPPORTED: "unsupported",
    PANIC: "panic",
}

TYPE_FLOAT, TYPE_INTEGER, TYPE_BOOL, TYPE_STRING, TYPE_POINT3, TYPE_VECTOR3, TYPE_RGB, TYPE_SPECTRUM = range(8)
TYPE_CODES = {
    "float": TYPE_FLOAT,
    "integer": TYPE_INTEGER,
    "bool": TYPE_BOOL,
    "string": TYPE_STRING,
    "point3": TYPE_POINT3,
    "vector3": TYPE_VECTOR3,
    "rgb": TYPE_RGB,
    "spectrum": TYPE_SPECTRUM,
}

EVENT_ESCAPED, EVENT_SCATTERED, EVENT_ABSORBED = range(3)
SPACE_SPECTRAL, SPACE_XYZ = range(2)
QUERY_INTEGRATE, QUERY_TRANSMITTANCE, QUERY_SCATTER = range(3)

FEATURES = {
    "emits": 1 << 0,
    "scatters": 1 << 1,
    "motion": 1 << 2,
    "refraction": 1 << 3,
    "embers": 1 << 4,
    "thick_lines": 1 << 5,
    "diffusion": 1 << 6,
    "emits_without_absorption": 1 << 7,
}

TABLES_EMISSION_GRID = 1 << 0

CREATE_FRAME = 1 << 0
CREATE_SHUTTER = 1 << 1
KIND_SCENE, KIND_FIRE, KIND_PBRT = 0, 1, 2

WEIGHTINGS = {"luminance": 0, "power": 1, "escaping": 2}

c_double_p = C.POINTER(C.c_double)
c_float_p = C.POINTER(C.c_float)


class FmParam(C.Structure):
    _fields_ = [("name", C.c_char_p), ("ty", C.c_uint32), ("count", C.c_uint32), ("values", C.c_void_p)]


class FmRay(C.Structure):
    _fields_ = [
        ("origin", C.c_double * 3),
        ("direction", C.c_double * 3),
        ("tmin", C.c_double),
        ("tmax", C.c_double),
        ("seed", C.c_uint64),
    ]


class FmExit(C.Structure):
    _fields_ = [("point", C.c_double * 3), ("direction", C.c_double * 3), ("t", C.c_double)]


class FmScatter(C.Structure):
    _fields_ = [("event", C.c_uint32), ("reserved", C.c_uint32), ("t", C.c_double), ("point", C.c_double * 3)]


class FmVolumeInfo(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("bounds_min", C.c_double * 3),
        ("bounds_max", C.c_double * 3),
        ("channels", C.c_uint32),
        ("channel_space", C.c_uint32),
        ("lambda_min", C.c_double),
        ("lambda_max", C.c_double),
        ("g", C.c_double),
        ("scatters", C.c_uint32),
        ("integrator", C.c_uint32),
        ("step", C.c_double),
        ("bytes", C.c_uint64),
        ("build_seconds", C.c_double),
        ("dims", C.c_uint32 * 3),
        ("reserved", C.c_uint32),
        ("lattice_min", C.c_double * 3),
        ("lattice_max", C.c_double * 3),
    ]


class FmMajorantGrid(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("bounds", C.c_double * 6),
        ("cell", C.c_double * 3),
        ("counts", C.c_uint32 * 3),
        ("reserved", C.c_uint32),
        ("sigma_t", c_double_p),
    ]


class FmTables(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("channels", C.c_uint32),
        ("rows", C.c_uint32),
        ("flags", C.c_uint32),
        ("reserved", C.c_uint32),
        ("dt", C.c_double),
        ("t_emit", C.c_double),
        ("absorption", c_float_p),
        ("scattering", c_float_p),
        ("emission", c_float_p),
    ]


class FmPointQuery(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("n", C.c_size_t),
        ("points", c_double_p),
        ("times", c_double_p),
        ("k", C.c_uint32),
        ("reserved", C.c_uint32),
        ("lambdas", c_double_p),
        ("sigma_a", c_double_p),
        ("sigma_s", c_double_p),
        ("le", c_double_p),
        ("j", c_double_p),
    ]


class FmErrorDetail(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("status", C.c_int32),
        ("reserved", C.c_int32),
        ("parameter", C.c_char_p),
        ("location", C.c_char_p),
        ("file", C.c_char_p),
        ("position", C.c_char_p),
        ("index", C.c_int64),
    ]


FmTask = C.CFUNCTYPE(None, C.c_void_p, C.c_size_t)
FmParallelFor = C.CFUNCTYPE(None, C.c_void_p, C.c_size_t, FmTask, C.c_void_p)


class FmCreateInfo(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("params", C.POINTER(FmParam)),
        ("locations", C.POINTER(C.c_char_p)),
        ("count", C.c_size_t),
        ("threads", C.c_uint32),
        ("flags", C.c_uint32),
        ("max_bytes", C.c_uint64),
        ("frame", C.c_int64),
        ("shutter", C.c_double * 2),
        ("parallel_for", C.c_void_p),
        ("pool", C.c_void_p),
        ("directory", C.c_char_p),
        ("kind", C.c_uint32),
        ("bins", C.c_uint32),
        ("wavelengths", C.c_double * 2),
    ]


class FmParamInfo(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("component", C.c_char_p),
        ("name", C.c_char_p),
        ("ty", C.c_char_p),
        ("default_value", C.c_char_p),
        ("unit", C.c_char_p),
        ("range", C.c_char_p),
        ("doc", C.c_char_p),
    ]


class FmLightInfo(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("power_w", C.c_double),
        ("power_lm", C.c_double),
        ("voxels", C.c_uint64),
        ("bytes", C.c_uint64),
        ("build_seconds", C.c_double),
        ("weighting", C.c_uint32),
        ("line_block", C.c_uint32),
    ]


class FmRayQuery(C.Structure):
    _fields_ = [
        ("struct_size", C.c_size_t),
        ("what", C.c_uint32),
        ("reserved", C.c_uint32),
        ("n", C.c_size_t),
        ("rays", C.POINTER(FmRay)),
        ("times", c_double_p),
        ("u", c_double_p),
        ("step", C.c_double),
        ("radiance", c_float_p),
        ("transmittance", c_float_p),
        ("exits", C.POINTER(FmExit)),
        ("events", C.POINTER(FmScatter)),
        ("weights", c_float_p),
    ]


_S = C.c_int32  # FmStatus
_V = C.c_void_p  # FmVolume*, FmLight*


class FmApi(C.Structure):
    _fields_ = [
        ("abi_major", C.c_uint32),
        ("abi_minor", C.c_uint32),
        ("struct_size", C.c_uint32),
        ("reserved", C.c_uint32),
        ("last_error", C.CFUNCTYPE(C.c_size_t, C.c_char_p, C.c_size_t)),
        ("last_error_detail", C.CFUNCTYPE(_S, C.POINTER(FmErrorDetail))),
        ("param_count", C.CFUNCTYPE(C.c_size_t)),
        ("param_info", C.CFUNCTYPE(_S, C.c_size_t, C.POINTER(FmParamInfo))),
        ("volume_create", C.CFUNCTYPE(_S, C.POINTER(FmCreateInfo), C.POINTER(_V))),
        ("volume_destroy", C.CFUNCTYPE(None, _V)),
        ("volume_info", C.CFUNCTYPE(_S, _V, C.POINTER(FmVolumeInfo))),
        ("volume_channel_xyz", C.CFUNCTYPE(_S, _V, c_double_p, C.c_size_t)),
        ("volume_temperature_range", C.CFUNCTYPE(_S, _V, c_double_p)),
        ("volume_white_temperature", C.CFUNCTYPE(_S, _V, c_double_p)),
        ("volume_capped_rays", C.CFUNCTYPE(_S, _V, C.POINTER(C.c_uint64))),
        ("volume_query", C.CFUNCTYPE(_S, _V, C.POINTER(FmRayQuery))),
        ("volume_features", C.CFUNCTYPE(_S, _V, C.POINTER(C.c_uint64))),
        ("volume_majorant_grid", C.CFUNCTYPE(_S, _V, C.POINTER(FmMajorantGrid))),
        ("volume_point", C.CFUNCTYPE(_S, _V, C.POINTER(FmPointQuery))),
        ("volume_coefficients", C.CFUNCTYPE(_S, _V, c_double_p, C.c_size_t, c_float_p, c_float_p, c_float_p)),
        ("light_create", C.CFUNCTYPE(_S, _V, C.POINTER(FmParam), C.c_size_t, C.POINTER(_V))),
        ("light_destroy", C.CFUNCTYPE(None, _V)),
        ("light_info", C.CFUNCTYPE(_S, _V, C.POINTER(FmLightInfo))),
        ("light_sample", C.CFUNCTYPE(_S, _V, c_double_p, c_double_p, C.c_size_t, c_double_p, c_double_p, c_float_p)),
        ("light_pdf", C.CFUNCTYPE(_S, _V, c_double_p, c_double_p, C.c_size_t, c_double_p)),
        ("light_pdf_direction", C.CFUNCTYPE(_S, _V, c_double_p, c_double_p, c_double_p, C.c_size_t, c_double_p)),
        ("light_integrate", C.CFUNCTYPE(_S, _V, C.POINTER(FmRay), c_double_p, C.c_size_t, c_float_p, c_float_p)),
        ("light_line_channels", C.CFUNCTYPE(_S, _V, C.POINTER(C.c_uint32))),
        # 1.1
        ("volume_note_count", C.CFUNCTYPE(_S, _V, C.POINTER(C.c_size_t))),
        ("volume_note", C.CFUNCTYPE(_S, _V, C.c_size_t, C.c_char_p, C.c_size_t, C.POINTER(C.c_size_t))),
        ("volume_tables", C.CFUNCTYPE(_S, _V, C.POINTER(FmTables))),
        ("volume_fields", C.CFUNCTYPE(_S, _V, c_double_p, C.c_size_t, c_float_p)),
        ("volume_bricks", C.CFUNCTYPE(_S, _V, C.POINTER(C.c_int64), C.c_size_t, C.POINTER(C.c_size_t))),
    ]
