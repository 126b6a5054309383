"""The API's documentation: each endpoint's OpenAPI text (:mod:`.openapi`) and examples
(:mod:`.examples`), the document the application serves at ``/openapi.json`` with the
pages ``/docs`` and ``/redoc`` (:mod:`.document`), and ``openapi.md`` rendered from it
(:mod:`.openapi_md`, ``make openapi``)."""
