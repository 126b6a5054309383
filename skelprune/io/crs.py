"""Coordinates on the Earth: a polygon in longitude/latitude pruned on the ground.

A degree of longitude is ``cos(latitude)`` of a degree of latitude on the ground (half
at 60° N), so a polygon rasterised in degrees is squeezed east–west and its medial axis
is not the ground's. A polygon in a geographic CRS (any that pyproj reads: ``EPSG:4326``,
``OGC:CRS84``, …) is projected to the azimuthal equidistant projection centred on its
bounding box (distances from the centre true, and within 1,000 km of it the scale off by
under 1.3 %: :data:`MAX_RADIUS`), pruned there in metres, and its lines mapped back. A
projected CRS (UTM, a national grid) is used as it is: lengths are in its units.

Without a CRS (no ``crs`` option, no ``crs`` member), a polygon is read as RFC 7946
longitude/latitude when its coordinates can hardly be anything else (:func:`guess_crs`:
within longitude/latitude bounds and at most :data:`GUESS_DEGREES` across), with a
warning that says so; otherwise as planar coordinates. ``crs="planar"`` says planar.

pyproj is the ``geo`` extra; it is imported only when a CRS is given or guessed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from ..errors import InvalidOptionError, InvalidPolygonError

__all__ = [
    "CRS_NAME",
    "GUESS_DEGREES",
    "GUESS_MIN_DEGREES",
    "MAX_RADIUS",
    "PLANAR",
    "RFC7946_CRS",
    "LocalProjection",
    "check_crs",
    "check_crs_name",
    "crs_name",
    "guess_crs",
    "local_projection",
]

#: The CRS names accepted: an authority and a code (``EPSG:4326``, ``OGC:CRS84``,
#: ``ESRI:102003``) or its OGC URN (``urn:ogc:def:crs:EPSG::32633``). Nothing else reaches
#: pyproj: a PROJ string or a file name could make PROJ open files.
CRS_NAME = re.compile(
    r"(?:[A-Z][A-Z0-9_]{0,31}:[A-Za-z0-9_.]{1,64}"
    r"|urn:ogc:def:crs:[A-Z][A-Z0-9_]{0,31}:[0-9.]{0,16}:[A-Za-z0-9_.]{1,64})"
)

#: Farthest a polygon may reach from the local projection's centre, in metres. The
#: azimuthal equidistant projection keeps distances from the centre; across, its scale
#: grows as ``θ/sin θ``: 1.3 % at 1,000 km.
MAX_RADIUS = 1_000_000.0

#: The CRS of RFC 7946 GeoJSON: longitude, latitude on WGS 84.
RFC7946_CRS = "OGC:CRS84"
#: The ``crs`` value that says the coordinates have none: planar, used as they are.
PLANAR = "planar"
#: Longest side, in coordinate units, of the bounding box of a polygon without a CRS that
#: is read as longitude/latitude (with its bounds). A degree is 111 km: a lake, a river
#: reach, a field or a town fits; a polygon in pixels or metres a unit across does not
#: exist in practice (the project's pixel and metre polygons are 4 to 10⁵ units across),
#: while one in pixels 60 units across (``examples/shape.geojson``) would, read as
#: degrees, be a 6,000 km shape. See docs/gis.md, "Which CRS, when none is given".
GUESS_DEGREES = 1.0
#: Smallest such extent: a polygon under 1e-6° (11 cm) across is no map feature, and
#: its projection would keep few of its digits; it stays planar.
GUESS_MIN_DEGREES = 1e-6


def _pyproj() -> Any:
    try:
        import pyproj
    except ImportError:  # pragma: no cover - the geo extra installs it
        raise InvalidOptionError(
            "a CRS needs pyproj: install skelprune[geo] (pip install 'skelprune[geo]')"
        ) from None
    return pyproj


def check_crs_name(name: str, what: str = "crs") -> str:
    """The name, if it is an authority code or its URN (:data:`CRS_NAME`).

    >>> check_crs_name("urn:ogc:def:crs:OGC:1.3:CRS84")
    'urn:ogc:def:crs:OGC:1.3:CRS84'
    >>> check_crs_name("/etc/passwd")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skelprune.errors.InvalidOptionError: crs: '/etc/passwd' is not a CRS name such as ...
    """
    if not CRS_NAME.fullmatch(name):
        raise InvalidOptionError(
            f"{what}: {name[:80]!r} is not a CRS name such as EPSG:4326, OGC:CRS84 or "
            "urn:ogc:def:crs:EPSG::32633"
        )
    return name


def crs_name(crs: Any) -> str | None:
    """The name of a pyproj or rasterio CRS object as :func:`check_crs_name` takes it:
    ``EPSG:code`` where it has one, else its authority and code (``ESRI:102003``); None
    for no CRS.

    A CRS with no authority at all is named ``?:?``, which :func:`check_crs_name`
    refuses with a clear error (its WKT would be refused too, and is no name).

    >>> import pyproj
    >>> crs_name(pyproj.CRS("EPSG:32633")), crs_name(pyproj.CRS("ESRI:102003"))
    ('EPSG:32633', 'ESRI:102003')
    """
    if crs is None:
        return None
    epsg = crs.to_epsg()
    return f"EPSG:{epsg}" if epsg else ":".join(crs.to_authority() or ("?", "?"))


def guess_crs(geom: Any) -> str | None:
    """The CRS of a polygon given without one: :data:`RFC7946_CRS` when every coordinate
    lies within longitude −180…180 and latitude −90…90 and its bounding box is at most
    :data:`GUESS_DEGREES` across (and at least :data:`GUESS_MIN_DEGREES`), else None
    (planar).

    >>> from shapely.geometry import box
    >>> guess_crs(box(10.0, 60.0, 10.02, 60.01)), guess_crs(box(0, 0, 60, 50))
    ('OGC:CRS84', None)
    """
    minx, miny, maxx, maxy = shapely.bounds(geom)
    within = -180 <= minx <= maxx <= 180 and -90 < miny <= maxy < 90
    if within and GUESS_MIN_DEGREES <= max(maxx - minx, maxy - miny) <= GUESS_DEGREES:
        return RFC7946_CRS
    return None


def has_pyproj() -> bool:
    """Whether pyproj (the ``geo`` extra) can be imported."""
    try:
        import pyproj  # noqa: F401
    except ImportError:  # pragma: no cover - the geo extra installs it
        return False
    return True


#: The Earth's equatorial radius as CRSs give it, in metres, within a few kilometres
#: (the ellipsoids of the Earth's datums): a CRS of another body is refused.
EARTH_RADIUS = (6_350_000.0, 6_400_000.0)


def _crs(name: str, what: str = "crs") -> Any:
    """The pyproj CRS of ``name``, refused (naming ``what``) when pyproj does not know
    it, or when it is no map of the Earth's surface: a vertical CRS (heights), a
    geocentric one (x, y, z from the Earth's centre), or one of another body (the Moon,
    Mars)."""
    check_crs_name(name, what)
    pyproj = _pyproj()
    try:
        crs = pyproj.CRS.from_user_input(name)
    except pyproj.exceptions.CRSError as exc:
        raise InvalidOptionError(
            f"{what}: {name!r} is not a CRS pyproj knows: {str(exc)[:200]}"
        ) from None
    if crs.is_vertical and not (crs.is_geographic or crs.is_projected):
        raise InvalidOptionError(f"{what}: {name} is a vertical CRS (heights); give a map CRS")
    if crs.is_geocentric:
        raise InvalidOptionError(
            f"{what}: {name} is a geocentric CRS (x, y, z from the Earth's centre); give a "
            "map CRS (geographic or projected)"
        )
    ellipsoid = crs.ellipsoid
    radius = None if ellipsoid is None else ellipsoid.semi_major_metre
    if radius is None or not EARTH_RADIUS[0] <= radius <= EARTH_RADIUS[1]:
        body = f"a body of radius {radius:,.0f} m" if radius else "no known body"
        raise InvalidOptionError(
            f"{what}: {name} is a CRS of {body}, not the Earth's; skelprune's "
            "geography is the Earth's"
        )
    return crs


def check_crs(name: str, what: str = "crs") -> str:
    """``name``, when it is a map CRS of the Earth pyproj knows (:func:`_crs`).

    >>> check_crs("EPSG:32633")
    'EPSG:32633'
    """
    _crs(name, what)
    return name


@dataclass(frozen=True)
class LocalProjection:
    """A geographic CRS and the local equidistant projection a polygon is pruned in.

    ``forward`` maps geometries or coordinates to metres, ``back`` maps ``(x, y)``
    arrays back to the input's CRS (longitude first, whatever the CRS's axis order).
    """

    crs: str  # the input's CRS, as given
    proj: str  # the local projection, as a PROJ string
    lon0: float
    lat0: float
    _to: Any
    _from: Any

    def forward(self, geom: Any) -> Any:
        return shapely.transform(geom, lambda xy: np.column_stack(self._to.transform(*xy.T)))

    def back(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lon, lat = self._from.transform(np.asarray(x, float), np.asarray(y, float))
        return np.asarray(lon), np.asarray(lat)

    def decimals(self, pixel_size: float) -> int:
        """Decimal places of degrees that resolve a thousandth of a pixel (as the
        frame's metres do)."""
        degree = 111_320.0 * max(math.cos(math.radians(abs(self.lat0))), 0.01)
        return math.ceil(3 - math.log10(pixel_size / degree) - 1e-9)


def is_geographic(name: str) -> bool:
    """Whether a CRS has longitude/latitude coordinates.

    >>> is_geographic("EPSG:4326"), is_geographic("EPSG:32633")
    (True, False)
    """
    return bool(_crs(name).is_geographic)


def local_projection(geom: Any, crs: str) -> LocalProjection | None:
    """The local projection for a polygon in ``crs`` (None: a projected CRS, used as it
    is).

    Raises
    ------
    InvalidPolygonError
        A polygon that crosses the antimeridian, reaches a pole, lies outside
        longitude/latitude, or reaches farther than :data:`MAX_RADIUS` from its centre:
        one local projection does not hold it (split it, or project it first).

    Examples
    --------
    >>> from shapely.geometry import box
    >>> p = local_projection(box(10.0, 60.0, 10.02, 60.01), "EPSG:4326")
    >>> g = p.forward(box(10.0, 60.0, 10.02, 60.01))
    >>> round(g.bounds[2] - g.bounds[0]), round(g.bounds[3] - g.bounds[1])  # metres
    (1116, 1114)
    """
    source = _crs(crs)
    if not source.is_geographic:
        return None
    pyproj = _pyproj()
    minx, miny, maxx, maxy = shapely.bounds(geom)
    if not (-180 <= minx <= maxx <= 180 and -90 < miny <= maxy < 90):
        raise InvalidPolygonError(
            f"coordinates outside longitude −180…180 and latitude −90…90 (open) in {crs}: "
            f"bounds {[minx, miny, maxx, maxy]}; a polygon that reaches a pole needs a "
            "projected CRS"
        )
    if maxx - minx > 180:
        raise InvalidPolygonError(
            "the polygon spans more than 180° of longitude (it crosses the antimeridian, or "
            "is wider than one local projection holds): split it at ±180°, or give it in a "
            "projected CRS"
        )
    lon0, lat0 = (minx + maxx) / 2, (miny + maxy) / 2
    proj = f"+proj=aeqd +lat_0={lat0:.9f} +lon_0={lon0:.9f} +datum=WGS84 +units=m +no_defs"
    local = pyproj.CRS.from_proj4(proj)
    to = pyproj.Transformer.from_crs(source, local, always_xy=True)
    back = pyproj.Transformer.from_crs(local, source, always_xy=True)
    p = LocalProjection(crs, proj, lon0, lat0, to, back)
    xy = shapely.get_coordinates(p.forward(shapely.get_exterior_ring(shapely.get_parts(geom))))
    reach = float(np.hypot(xy[:, 0], xy[:, 1]).max()) if len(xy) else 0.0
    if not math.isfinite(reach) or reach > MAX_RADIUS:
        raise InvalidPolygonError(
            f"the polygon reaches {reach / 1000:.0f} km from its centre, more than one "
            f"local projection holds ({MAX_RADIUS / 1000:.0f} km): split it, or give it "
            "in a projected CRS"
        )
    return p
