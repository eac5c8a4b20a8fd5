// The lower module.
#pragma once
