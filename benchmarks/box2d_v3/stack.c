/* carom's harness around Box2D v3 (C): a stack of unit boxes, sleep off, and its energy.
 *
 * n unit squares (density 1, friction 0.6) stacked exactly touching on a static 20 m x 1 m
 * ground, gravity 9.81 m/s^2, stepped at 60 Hz with 4 substeps for the given seconds. Prints
 * one line: the largest rise of the mechanical energy above an earlier minimum [J] (summed in
 * double from Box2D's float state), the largest sideways move of any box [m] and the top
 * box's sink at the end [m]. benchmarks/stacks.py builds and runs it.
 */
#include "box2d/box2d.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main( int argc, char** argv )
{
	int n = argc > 1 ? atoi( argv[1] ) : 10;
	double seconds = argc > 2 ? atof( argv[2] ) : 30.0;
	if ( n < 1 || n > 256 )
	{
		fprintf( stderr, "boxes: 1 to 256\n" );
		return 2;
	}
	b2WorldDef worldDef = b2DefaultWorldDef();
	worldDef.enableSleep = false;
	worldDef.gravity = ( b2Vec2 ){ 0.0f, -9.81f };
	b2WorldId world = b2CreateWorld( &worldDef );

	b2BodyDef groundDef = b2DefaultBodyDef();
	groundDef.position = ( b2Vec2 ){ 0.0f, -0.5f };
	b2BodyId ground = b2CreateBody( world, &groundDef );
	b2ShapeDef groundShape = b2DefaultShapeDef();
	groundShape.material.friction = 0.6f;
	b2Polygon slab = b2MakeBox( 10.0f, 0.5f );
	b2CreatePolygonShape( ground, &groundShape, &slab );

	b2BodyId boxes[256];
	b2Polygon square = b2MakeSquare( 0.5f );
	for ( int k = 0; k < n; ++k )
	{
		b2BodyDef def = b2DefaultBodyDef();
		def.type = b2_dynamicBody;
		def.position = ( b2Vec2 ){ 0.0f, 0.5f + (float)k };
		boxes[k] = b2CreateBody( world, &def );
		b2ShapeDef shape = b2DefaultShapeDef();
		shape.density = 1.0f;
		shape.material.friction = 0.6f;
		b2CreatePolygonShape( boxes[k], &shape, &square );
	}

	int steps = (int)lround( seconds * 60.0 );
	double lowest = INFINITY, rise = 0.0, sway = 0.0;
	for ( int step = 0; step <= steps; ++step )
	{
		if ( step > 0 )
		{
			b2World_Step( world, 1.0f / 60.0f, 4 );
		}
		double energy = 0.0;
		for ( int k = 0; k < n; ++k )
		{
			b2Vec2 p = b2Body_GetPosition( boxes[k] );
			b2Vec2 v = b2Body_GetLinearVelocity( boxes[k] );
			double w = b2Body_GetAngularVelocity( boxes[k] );
			/* a unit square of 1 kg: I = 1/6 kg m^2 */
			energy += 0.5 * ( (double)v.x * v.x + (double)v.y * v.y ) + w * w / 12.0 + 9.81 * p.y;
			sway = fmax( sway, fabs( (double)p.x ) );
		}
		rise = fmax( rise, energy - lowest );
		lowest = fmin( lowest, energy );
	}
	double sink = (double)b2Body_GetPosition( boxes[n - 1] ).y - ( n - 0.5 );
	printf( "rise_J %.6e sway_m %.6e sink_m %.7f\n", rise, sway, sink );
	b2DestroyWorld( world );
	return 0;
}
