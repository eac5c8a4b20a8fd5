// The page of report.html, compiled in: the build turns the template src/reports/report_page.html into
// report_page.cpp in the build tree (scripts/embed_text.cmake), so the page is edited as HTML and the
// program needs no file at run time.
#pragma once

namespace city3d::detail {

/// The page up to where the run's data goes (the marker @REPORT_DATA@ in the template), NUL-terminated.
extern const char kReportPageHead[];
/// The page after the run's data, to its end, NUL-terminated.
extern const char kReportPageTail[];

}  // namespace city3d::detail
